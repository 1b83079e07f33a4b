//! Speed measurement in pulse-count and period mode (spec section 5).
//!
//! Generated waveforms are sampled at the reference clock (f = 1 MHz, so the
//! sample index is the capture timer's tick), decoded, and fed edge by edge
//! to the estimator, which closes a window every T = 10 ms. Every estimate is
//! compared with the true average speed over the span it reports:
//!
//! * pulse mode: over the window; the error must be below the reported
//!   resolution `K / W (1 + edge_spread)`, where the configured
//!   `edge_spread` (counts) is how far the encoder's phase and duty-cycle
//!   errors move single edges (the generator's value; 0 for an ideal
//!   encoder);
//! * period mode: over the span between the true instants of its first and
//!   last edge; the error must be below the reported resolution
//!   `S / (C - 1)` (with `M = 4` edges per span the channel errors cancel);
//! * standstill: over the quiet span; below the reported `K / E (1 + edge_spread)`.
//!
//! The mode switch is checked for chatter with speeds hovering at each
//! threshold.

mod common;

use common::{EncoderModel, Profile, Waveform, accelerating, constant, jittered, reversing};
use locus_core::cast;
use locus_odometry::counter::Counter;
use locus_odometry::error::Error;
use locus_odometry::quadrature::{Direction, QuadratureDecoder};
use locus_odometry::speed::{Estimate, Mode, SpeedConfig, SpeedEstimator};
use locus_odometry::wheel::Real;
use proptest::prelude::*;

/// The reference clock, Hz (= the sampling rate of the generated waveforms).
const F: f64 = 1.0e6;

/// How an estimate was measured, for the checks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Class {
    Pulse,
    Span,
    Standstill,
}

const CLASSES: [Class; 3] = [Class::Pulse, Class::Span, Class::Standstill];

/// One estimate next to the truth.
#[derive(Debug, Clone, Copy)]
struct Checked {
    est: Estimate<f64>,
    truth: f64,
    class: Class,
    /// The error the estimate may have: its resolution, widened by the
    /// encoder's edge spread where that applies.
    bound: f64,
}

impl Checked {
    fn err(&self) -> f64 {
        (self.est.speed - self.truth).abs()
    }
    /// Error in units of the reported resolution.
    fn ratio(&self) -> f64 {
        self.err() / self.est.resolution
    }
}

/// The outcome of one run.
struct Run {
    checked: Vec<Checked>,
    switches: u32,
    final_mode: Mode,
    /// Rounding allowance of the scalar type, relative.
    eps: f64,
}

impl Run {
    /// Asserts every estimate is within its bound.
    fn check(&self, what: &str) {
        for c in &self.checked {
            let slack = self.eps * (c.est.speed.abs() + c.truth.abs()) + 1e-12;
            assert!(
                c.err() <= c.bound + slack,
                "{what}: error {:.3e} > bound {:.3e}: {c:?}",
                c.err(),
                c.bound
            );
        }
    }
    /// The largest error / resolution of the estimates of a class (0 if none).
    fn worst(&self, class: Class) -> f64 {
        self.checked
            .iter()
            .filter(|c| c.class == class)
            .map(Checked::ratio)
            .fold(0.0, f64::max)
    }
    fn count(&self, class: Class) -> usize {
        self.checked.iter().filter(|c| c.class == class).count()
    }
}

/// Decodes `ticks` samples of `wave` (at 1 MHz) with glitches of probability
/// `glitch_prob`, feeds the estimator, and checks nothing yet.
fn run<T: Real>(
    wave: &Waveform,
    config: SpeedConfig<T>,
    ticks: u64,
    glitch_prob: f64,
    seed: u64,
) -> Run {
    assert_eq!(wave.sample_hz, F);
    // The estimator is told the encoder's edge spread, as a user would
    // configure it from the encoder's datasheet.
    let config = SpeedConfig {
        edge_spread: cast(wave.encoder.spread_counts()),
        ..config
    };
    let mut samples = wave.samples(ticks, glitch_prob, seed);
    let first = samples.next().expect("samples");
    let mut dec = QuadratureDecoder::new(first.levels.0, first.levels.1, Counter::paper());
    let mut est = SpeedEstimator::new(config, 0).expect("valid config");
    let mut checked = Vec::new();
    let avg = |t0: f64, t1: f64| (wave.travel(t1) - wave.travel(t0)) / (t1 - t0);
    for s in samples {
        let tick = s.tick as u32;
        est.on_transition(tick, dec.update(s.levels.0, s.levels.1));
        let Some(e) = est.poll(tick) else { continue };
        let est = Estimate {
            speed: e.speed.to_f64(),
            mode: e.mode,
            resolution: e.resolution.to_f64(),
            from_tick: e.from_tick,
            to_tick: e.to_tick,
        };
        let (t0, t1) = (f64::from(e.from_tick) / F, f64::from(e.to_tick) / F);
        let (class, truth, bound) = match e.mode {
            Mode::Pulse => (Class::Pulse, avg(t0, t1), est.resolution),
            Mode::Period if est.speed == 0.0 => (Class::Standstill, avg(t0, t1), est.resolution),
            Mode::Period => {
                let te0 = wave.edge_time(u64::from(e.from_tick));
                let te1 = wave.edge_time(u64::from(e.to_tick));
                (Class::Span, avg(te0, te1), est.resolution)
            }
        };
        checked.push(Checked {
            est,
            truth,
            class,
            bound,
        });
    }
    Run {
        checked,
        switches: est.mode_switches(),
        final_mode: est.mode(),
        eps: 4.0
            * if size_of::<T>() == 4 {
                f64::from(f32::EPSILON)
            } else {
                f64::EPSILON
            },
    }
}

/// `n` speeds log-spaced over [lo, hi], m/s.
fn log_speeds(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
        .collect()
}

/// The encoder of most tests: 10 deg phase error, 45 % / 55 % duty.
fn imperfect() -> EncoderModel {
    EncoderModel::with_errors(10.0, 0.45, 0.55)
}

fn paper() -> SpeedConfig<f32> {
    SpeedConfig::paper()
}

fn pulse_only() -> SpeedConfig<f32> {
    SpeedConfig {
        initial_mode: Mode::Pulse,
        to_period_below: 0,
        ..paper()
    }
}

fn period_only(edges: u32) -> SpeedConfig<f32> {
    SpeedConfig {
        initial_mode: Mode::Period,
        to_pulse_above: u32::MAX,
        period_edges: edges,
        ..paper()
    }
}

/// Worst error / resolution per class over a set of runs.
fn worst(runs: &[Run]) -> [f64; 3] {
    CLASSES.map(|c| runs.iter().map(|r| r.worst(c)).fold(0.0, f64::max))
}

fn counts(runs: &[Run]) -> [usize; 3] {
    CLASSES.map(|c| runs.iter().map(|r| r.count(c)).sum())
}

#[test]
fn constant_speeds_from_1_cm_s_to_2_m_s_are_within_resolution() {
    // 25 speeds, both directions, ideal and imperfect channels; the paper's
    // configuration (switching) and each mode forced over the whole range.
    let speeds = log_speeds(0.01, 2.0, 25);
    let configs = [
        ("switching", paper()),
        ("pulse only", pulse_only()),
        ("period only M=4", period_only(4)),
    ];
    for (name, config) in configs {
        for enc in [EncoderModel::ideal(), imperfect()] {
            let mut runs = Vec::new();
            for &v in &speeds {
                for v in [v, -v] {
                    let wave = Waveform::new(enc, constant(v, 1.234e-4), F);
                    let r = run(&wave, config, 200_000, 0.0, 0);
                    r.check(&format!("{name}, v = {v}, {enc:?}"));
                    runs.push(r);
                }
            }
            let w = worst(&runs);
            eprintln!(
                "{name:>16}, spread {:.2} counts: max |err|/resolution  pulse {:.3} (n={})  period {:.3} (n={})  standstill {:.3} (n={})",
                enc.spread_counts(),
                w[0],
                counts(&runs)[0],
                w[1],
                counts(&runs)[1],
                w[2],
                counts(&runs)[2],
            );
            if name == "pulse only" {
                assert_eq!(counts(&runs)[1] + counts(&runs)[2], 0);
            }
            if name == "period only M=4" {
                assert!(counts(&runs)[1] > 850);
            }
        }
    }
}

#[test]
fn period_mode_with_one_edge_is_the_spec_formula_and_needs_ideal_channels() {
    // M = 1: S = pi R f / (2 N C G), resolution ~ S^2 2 N G / (pi R f).
    let speeds = log_speeds(0.01, 2.0, 13);
    let mut ideal = Vec::new();
    let mut skewed = Vec::new();
    for &v in &speeds {
        let r = run(
            &Waveform::new(EncoderModel::ideal(), constant(v, 0.0), F),
            period_only(1),
            100_000,
            0.0,
            0,
        );
        r.check(&format!("M = 1, ideal, v = {v}"));
        for c in r.checked.iter().filter(|c| c.class == Class::Span) {
            let ticks = f64::from(c.est.to_tick - c.est.from_tick);
            let k = core::f64::consts::PI * 0.05 * F / (2.0 * 500.0);
            assert!((c.est.speed / (k / ticks) - 1.0).abs() < 1e-6, "{c:?}");
            // The reported one-tick step S / (C - 1) is the spec's
            // S^2 2 N G / (pi R f) = S / C times C / (C - 1).
            let spec = c.est.speed * c.est.speed * 2.0 * 500.0 / (core::f64::consts::PI * 0.05 * F);
            assert!(
                (c.est.resolution / spec - ticks / (ticks - 1.0)).abs() < 1e-5,
                "{c:?} vs {spec}"
            );
        }
        ideal.push(r);
        let r = run(
            &Waveform::new(imperfect(), constant(v, 0.0), F),
            period_only(1),
            100_000,
            0.0,
            0,
        );
        skewed.push(r);
    }
    let (wi, ws) = (worst(&ideal)[1], worst(&skewed)[1]);
    eprintln!(
        "period mode M = 1: max |err|/resolution ideal {wi:.3}, with 10 deg phase / 45-55 % duty {ws:.1}"
    );
    assert!(wi <= 1.0);
    // With channel errors single edge intervals are off by up to 20 %: far
    // beyond the resolution, which is why the default spans M = 4 edges.
    assert!(ws > 10.0);
}

/// A profile kind for the property test.
fn profile(kind: u8, v: f64, s0: f64) -> Profile {
    match kind {
        0 => constant(v, s0),
        // From v to about -v over the 0.3 s run: through zero.
        1 => accelerating(v, -2.0 * v / 0.3, s0),
        // Back and forth, peak speed |v|, one reversal every 0.1 s.
        2 => reversing(v / (2.0 * core::f64::consts::PI * 5.0), 5.0, s0),
        _ => jittered(v, vec![(0.2 * v, 13.0, 0.4), (0.1 * v, 71.0, 2.0)], s0),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Constant, accelerating (through zero), reversing and jittered speeds
    /// up to 2 m/s, random channel errors, occasional glitches: every
    /// estimate of the paper's configuration is within its mode's bound.
    #[test]
    fn every_estimate_is_within_its_resolution(
        speed in (-2.0f64..0.301).prop_map(|e| 10f64.powf(e)),
        backwards in any::<bool>(),
        kind in 0u8..4,
        phase in -15.0f64..15.0,
        duty_a in 0.44f64..0.56,
        duty_b in 0.44f64..0.56,
        s0 in 0.0f64..0.001,
        glitch_prob in prop_oneof![Just(0.0), 1e-6f64..1e-4],
        seed in any::<u64>(),
    ) {
        let v = if backwards { -speed } else { speed };
        let wave = Waveform::new(EncoderModel::with_errors(phase, duty_a, duty_b), profile(kind, v, s0), F);
        let r = run(&wave, paper(), 300_000, glitch_prob, seed);
        r.check("proptest");
    }
}

#[test]
fn accelerating_through_the_thresholds_switches_once() {
    // 0.01 -> 2 m/s in 1 s and back down: one switch each way, no chatter.
    let up = run(
        &Waveform::new(imperfect(), accelerating(0.01, 1.99, 0.0), F),
        paper(),
        1_000_000,
        0.0,
        0,
    );
    up.check("accelerating");
    assert_eq!(up.switches, 1);
    assert_eq!(up.final_mode, Mode::Pulse);
    // (Starting in pulse mode, as a robot already at 2 m/s would be.)
    let fast_start = SpeedConfig {
        initial_mode: Mode::Pulse,
        ..paper()
    };
    let down = run(
        &Waveform::new(imperfect(), accelerating(2.0, -1.99, 0.0), F),
        fast_start,
        1_000_000,
        0.0,
        0,
    );
    down.check("decelerating");
    assert_eq!(down.switches, 1);
    assert_eq!(down.final_mode, Mode::Period);
    let [p, s, z] = worst(&[up, down]);
    eprintln!(
        "accelerating/decelerating 0.01 <-> 2 m/s: max |err|/resolution pulse {p:.3} period {s:.3} standstill {z:.3}"
    );
}

#[test]
fn reversing_switches_at_most_twice_per_reversal() {
    // 0.1 m amplitude at 1 Hz (peak 0.63 m/s) for 2 s: 4 reversals.
    let r = run(
        &Waveform::new(imperfect(), reversing(0.1, 1.0, 0.0), F),
        paper(),
        2_000_000,
        1e-5,
        7,
    );
    r.check("reversing");
    let [p, s, z] = worst(core::slice::from_ref(&r));
    eprintln!(
        "reversing 2 s: {} switches for 4 reversals; max |err|/resolution pulse {p:.3} period {s:.3} standstill {z:.3}",
        r.switches
    );
    // Start in period mode -> pulse, then period and back around each reversal.
    assert!(r.switches <= 1 + 2 * 4, "{}", r.switches);
    // The sign follows the direction.
    let fast: Vec<_> = r.checked.iter().filter(|c| c.truth.abs() > 0.3).collect();
    assert!(
        fast.iter()
            .all(|c| c.est.speed.signum() == c.truth.signum())
    );
}

#[test]
fn standstill_reads_zero_in_period_mode() {
    let wave = Waveform::new(imperfect(), constant(0.0, 3.3e-4), F);
    let r = run(&wave, paper(), 300_000, 0.0, 0);
    r.check("standstill");
    assert!(
        r.checked
            .iter()
            .all(|c| c.est.speed == 0.0 && c.est.mode == Mode::Period)
    );
    // The bound K / E (1 + edge_spread) tightens as the quiet span grows.
    let last = r.checked.last().unwrap();
    assert_eq!(last.est.from_tick, 0);
    let expected = paper().speed_scale() as f64 / f64::from(last.est.to_tick)
        * (1.0 + wave.encoder.spread_counts());
    assert!((last.est.resolution - expected).abs() < 1e-9);
    assert_eq!(r.switches, 0);
}

#[test]
fn stopping_reads_zero_after_the_timeout() {
    // 0.05 m/s, then stopped at t = 0.1 s (speed changes abruptly).
    let profile: Profile = Box::new(|t: f64| 0.05 * t.min(0.1));
    let r = run(
        &Waveform::new(EncoderModel::ideal(), profile, F),
        paper(),
        400_000,
        0.0,
        0,
    );
    r.check("stop");
    let after: Vec<_> = r
        .checked
        .iter()
        .filter(|c| c.est.to_tick > 210_000)
        .collect();
    assert!(
        !after.is_empty()
            && after
                .iter()
                .all(|c| c.est.speed == 0.0 && c.class == Class::Standstill)
    );
}

#[test]
fn double_precision_estimator_is_within_resolution() {
    let config = SpeedConfig::<f64>::paper();
    for v in log_speeds(0.01, 2.0, 9) {
        let r = run(
            &Waveform::new(imperfect(), constant(-v, 0.0), F),
            config,
            100_000,
            0.0,
            0,
        );
        r.check("f64");
    }
}

/// Runs a jittered speed hovering around `counts` counts per window and
/// returns the number of mode switches (also checking every estimate).
fn hover(config: SpeedConfig<f32>, counts: f64, jitter: Vec<(f64, f64, f64)>, phase: f64) -> u32 {
    let enc = EncoderModel::with_errors(phase, 0.48, 0.53);
    // Counts per 10 ms window at 1 m/s.
    let per_mps = 0.01 * 4.0 * enc.lines_per_metre();
    let wave = Waveform::new(enc, jittered(counts / per_mps, jitter, 0.0), F);
    let r = run(&wave, config, 1_000_000, 0.0, 0);
    r.check("hover");
    r.switches
}

/// Up to three jitter components whose amplitudes sum to at most `max_counts`
/// counts per window (in m/s), 0.5 to 40 Hz.
fn jitter(max_counts: f64) -> impl Strategy<Value = Vec<(f64, f64, f64)>> {
    let per_mps = 0.01 * 4.0 * EncoderModel::ideal().lines_per_metre();
    prop::collection::vec((0.0f64..1.0, 0.5f64..40.0, 0.0f64..6.3), 1..=3).prop_map(move |v| {
        let total: f64 = v.iter().map(|c| c.0).sum::<f64>().max(1e-9);
        v.into_iter()
            .map(|(a, f, p)| (a / total * max_counts / per_mps, f, p))
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// A speed hovering at the lower threshold (8 counts per window, +-0.4
    /// counts, jitter up to +-1.5 counts) switches to period mode at most
    /// once and never back: the count cannot reach 12.
    #[test]
    fn hovering_at_the_lower_threshold_switches_at_most_once(
        offset in -0.4f64..0.4,
        jitter in jitter(1.5),
        phase in -10.0f64..10.0,
    ) {
        let config = SpeedConfig { initial_mode: Mode::Pulse, ..paper() };
        let switches = hover(config, 8.0 + offset, jitter, phase);
        prop_assert!(switches <= 1, "{} switches", switches);
    }

    /// The same at the upper threshold (12 counts per window), starting in
    /// period mode.
    #[test]
    fn hovering_at_the_upper_threshold_switches_at_most_once(
        offset in -0.4f64..0.4,
        jitter in jitter(1.5),
        phase in -10.0f64..10.0,
    ) {
        let switches = hover(paper(), 12.0 + offset, jitter, phase);
        prop_assert!(switches <= 1, "{} switches", switches);
    }
}

#[test]
fn without_hysteresis_the_same_speed_chatters() {
    // Control for the two properties above: one threshold (10 counts) and a
    // speed hovering at it chatters; the 8/12 band does not.
    let jitter = vec![(0.015, 3.0, 0.0), (0.008, 17.0, 1.0)];
    let single = SpeedConfig {
        to_period_below: 10,
        to_pulse_above: 10,
        ..paper()
    };
    let chatter = hover(single, 10.0, jitter.clone(), 5.0);
    let low = hover(
        SpeedConfig {
            initial_mode: Mode::Pulse,
            ..paper()
        },
        8.0,
        jitter.clone(),
        5.0,
    );
    let high = hover(paper(), 12.0, jitter, 5.0);
    eprintln!(
        "1 s hovering (+-1.5 counts of jitter): single threshold at 10: {chatter} switches; 8/12 hysteresis at 8: {low}, at 12: {high}"
    );
    assert!(chatter >= 5, "{chatter}");
    assert!(low <= 1 && high <= 1);
}

#[test]
fn configuration_and_windows_are_validated() {
    assert!(SpeedEstimator::new(paper(), 0).is_ok());
    let bad = [
        SpeedConfig {
            to_period_below: 13,
            ..paper()
        },
        SpeedConfig {
            period_edges: 0,
            ..paper()
        },
        SpeedConfig {
            period_edges: 17,
            ..paper()
        },
        SpeedConfig {
            clock_hz: 0,
            ..paper()
        },
        SpeedConfig {
            window: 0.0,
            ..paper()
        },
        SpeedConfig {
            window: f32::NAN,
            ..paper()
        },
        SpeedConfig {
            window: 1e-7,
            ..paper()
        }, // under one tick
        SpeedConfig {
            standstill_timeout: -1.0,
            ..paper()
        },
        SpeedConfig {
            wheel: locus_odometry::wheel::Wheel::new(0, 1.0, 0.05),
            ..paper()
        },
        SpeedConfig {
            wheel: locus_odometry::wheel::Wheel::new(500, 1.0, f32::INFINITY),
            ..paper()
        },
    ];
    for c in bad {
        assert!(
            matches!(SpeedEstimator::new(c, 0), Err(Error::InvalidParameter(_))),
            "{c:?}"
        );
    }
    assert_eq!(paper().window_ticks(), 10_000);
    assert_eq!(paper().standstill_ticks(), 100_000);
    let mut est = SpeedEstimator::new(paper(), 5).unwrap();
    assert!(matches!(est.end_window(5), Err(Error::InvalidParameter(_))));
    assert!(est.poll(10_004).is_none());
    assert!(est.poll(10_005).is_some());
}

#[test]
fn time_stamps_may_wrap() {
    // The capture timer wraps through 2^32 in the middle of a span and a
    // window: the same estimates as without the wrap.
    let start = u32::MAX - 15_000;
    let mut a = SpeedEstimator::new(paper(), start).unwrap();
    let mut b = SpeedEstimator::new(paper(), 0).unwrap();
    for i in 1..=30u32 {
        a.on_edge(start.wrapping_add(i * 1_500), Direction::Reverse);
        b.on_edge(i * 1_500, Direction::Reverse);
    }
    for w in 1..=5u32 {
        let (ea, eb) = (
            a.end_window(start.wrapping_add(w * 10_000)).unwrap(),
            b.end_window(w * 10_000).unwrap(),
        );
        assert_eq!(
            (ea.speed, ea.mode, ea.resolution),
            (eb.speed, eb.mode, eb.resolution)
        );
        assert_eq!(ea.from_tick, start.wrapping_add(eb.from_tick));
    }
    // 1 edge per 1500 ticks in reverse: -K * 4 / 6000 in period mode.
    let e = b.end_window(51_000).unwrap();
    assert_eq!(e.mode, Mode::Period);
    assert!(
        (e.speed + paper().speed_scale() * 4.0 / 6_000.0).abs() < 1e-6,
        "{e:?}"
    );
    assert_eq!((e.from_tick, e.to_tick), (39_000, 45_000));
}

#[test]
fn reset_forgets_history_but_keeps_the_switch_count() {
    let mut est = SpeedEstimator::new(paper(), 0).unwrap();
    for i in 1..=200u32 {
        est.on_edge(i * 50, Direction::Forward);
    }
    let e = est.end_window(10_000).unwrap();
    assert_eq!(
        (e.mode, est.mode(), est.mode_switches()),
        (Mode::Pulse, Mode::Pulse, 1)
    );
    assert!((f64::from(e.speed) - 200.0 * 157.079_63 / 10_000.0).abs() < 1e-4);
    est.reset(20_000);
    assert_eq!(
        (est.mode(), est.mode_switches(), est.window_count()),
        (Mode::Period, 1, 0)
    );
    let e = est.end_window(30_000).unwrap();
    assert_eq!((e.speed, e.mode, e.from_tick), (0.0, Mode::Period, 20_000));
}
