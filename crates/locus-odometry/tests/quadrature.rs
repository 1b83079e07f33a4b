//! x4 quadrature decoding and the wrapping counter (spec section 5).
//!
//! Generated waveforms (constant, accelerating and reversing speeds, phase
//! error between A and B, duty-cycle error, one-sample glitches on both
//! channels) are decoded sample by sample; the decoded count must equal the
//! generator's true edge count exactly, and every glitch must show up as
//! invalid transitions, never as counts.

mod common;

use common::{EncoderModel, Profile, Waveform, accelerating, constant, jittered, reversing};
use locus_odometry::counter::{Counter, PAPER_BITS, wrapping_diff};
use locus_odometry::error::Error;
use locus_odometry::quadrature::{Direction, QuadratureDecoder, Transition, decode};
use locus_odometry::source::EncoderSource;
use proptest::prelude::*;

/// What decoding a waveform gave, next to the truth.
#[derive(Debug)]
struct Outcome {
    /// Net count from the decoder's counter (wrap-safe difference).
    decoded_net: i64,
    /// Net true count (last sample minus first).
    true_net: i64,
    /// Count transitions the decoder reported.
    decoded_edges: u64,
    /// True edges (sum of |count change| between samples).
    true_edges: u64,
    /// Invalid transitions the decoder counted.
    invalid: u32,
    /// Glitches the generator injected.
    glitches: u64,
    /// Count transitions reported at a glitched sample or just after it.
    counted_at_glitch: u64,
}

/// Decodes `n` samples of `wave` into a 20-bit counter starting at `start`.
fn decode_wave(wave: &Waveform, n: u64, glitch_prob: f64, seed: u64, start: u32) -> Outcome {
    let mut samples = wave.samples(n, glitch_prob, seed);
    let first = samples.next().expect("at least one sample");
    assert!(!first.glitch);
    let mut counter = Counter::paper();
    counter.set(start);
    let mut dec = QuadratureDecoder::new(first.levels.0, first.levels.1, counter);
    let (mut decoded_edges, mut true_edges, mut glitches, mut counted_at_glitch) = (0, 0, 0, 0);
    let mut prev_true = first.true_count;
    let mut after_glitch = false;
    for s in samples {
        let t = dec.update(s.levels.0, s.levels.1);
        if let Transition::Count(_) = t {
            decoded_edges += 1;
            if s.glitch || after_glitch {
                counted_at_glitch += 1;
            }
        }
        glitches += u64::from(s.glitch);
        after_glitch = s.glitch;
        true_edges += (s.true_count - prev_true).unsigned_abs();
        prev_true = s.true_count;
    }
    Outcome {
        decoded_net: i64::from(dec.counter().since(start)),
        true_net: prev_true - first.true_count,
        decoded_edges,
        true_edges,
        invalid: dec.invalid_transitions(),
        glitches,
        counted_at_glitch,
    }
}

fn assert_exact(o: &Outcome) {
    assert_eq!(o.decoded_net, o.true_net, "{o:?}");
    assert_eq!(o.decoded_edges, o.true_edges, "{o:?}");
    assert_eq!(u64::from(o.invalid), 2 * o.glitches, "{o:?}");
    assert_eq!(o.counted_at_glitch, 0, "{o:?}");
}

/// A sampling rate with at least `margin` samples between the two closest
/// edges at speed `v_max` (m/s).
fn sample_hz(enc: &EncoderModel, v_max: f64, margin: f64) -> f64 {
    let closest_edges_s = enc.min_edge_gap() / (v_max * enc.lines_per_metre());
    margin / closest_edges_s
}

/// Encoder channel errors: phase error (deg), duty cycles of A and B.
fn channel_errors() -> impl Strategy<Value = EncoderModel> {
    (-20.0f64..20.0, 0.42f64..0.58, 0.42f64..0.58)
        .prop_map(|(p, a, b)| EncoderModel::with_errors(p, a, b))
}

#[test]
fn transition_table_is_exhaustive() {
    // Forward order of the states: 00 -> 10 -> 11 -> 01.
    let order = [(false, false), (true, false), (true, true), (false, true)];
    for (i, &from) in order.iter().enumerate() {
        for (j, &to) in order.iter().enumerate() {
            let expected = match (j + 4 - i) % 4 {
                0 => Ok(None),
                1 => Ok(Some(Direction::Forward)),
                3 => Ok(Some(Direction::Reverse)),
                _ => Err(Error::InvalidTransition),
            };
            assert_eq!(decode(from, to), expected, "{from:?} -> {to:?}");
            // Invalid exactly when both bits change.
            let both = from.0 != to.0 && from.1 != to.1;
            assert_eq!(decode(from, to).is_err(), both);
            // The stateful decoder agrees and counts only valid edges.
            let mut dec = QuadratureDecoder::new(from.0, from.1, Counter::paper());
            let t = dec.update(to.0, to.1);
            let expected_t = match expected {
                Ok(None) => Transition::Hold,
                Ok(Some(d)) => Transition::Count(d),
                Err(_) => Transition::Invalid,
            };
            assert_eq!(t, expected_t);
            assert_eq!(
                dec.counter().since(0),
                expected.map_or(0, |d| d.map_or(0, Direction::sign))
            );
            assert_eq!(dec.invalid_transitions(), u32::from(both));
            assert_eq!(dec.levels(), to);
        }
    }
}

#[test]
fn forward_means_a_leads_b() {
    // A rises first, then B: forward, counting up; reversed order counts down.
    let mut dec = QuadratureDecoder::new(false, false, Counter::paper());
    for (a, b) in [(true, false), (true, true), (false, true), (false, false)] {
        assert_eq!(dec.update(a, b), Transition::Count(Direction::Forward));
    }
    assert_eq!(dec.counter().value(), 4);
    for (a, b) in [(false, true), (true, true), (true, false), (false, false)] {
        assert_eq!(dec.update(a, b), Transition::Count(Direction::Reverse));
    }
    assert_eq!(dec.counter().value(), 0);
}

#[test]
fn glitch_on_an_edge_is_indistinguishable_from_motion() {
    // Documents a limit of any level-sampling decoder: true levels 00 -> 10
    // (one forward edge) with the second sample glitched to 01 read as one
    // reverse edge, a valid transition. The generator therefore places
    // glitches only where no real edge is adjacent.
    let mut dec = QuadratureDecoder::new(false, false, Counter::paper());
    assert_eq!(
        dec.update(false, true),
        Transition::Count(Direction::Reverse)
    );
    assert_eq!(dec.invalid_transitions(), 0);
}

#[test]
fn constant_speed_ideal_encoder_is_exact_in_both_directions() {
    for v in [0.01, 0.3, 2.0, -0.01, -0.3, -2.0] {
        let enc = EncoderModel::ideal();
        let hz = sample_hz(&enc, 2.0, 4.0);
        let wave = Waveform::new(enc, constant(v, 0.0123), hz);
        let n = (0.05 * hz) as u64;
        let o = decode_wave(&wave, n, 0.0, 1, 0);
        assert_exact(&o);
        // x4: 4 N G counts per wheel revolution of 2 pi R.
        let expected = v * 0.05 * enc.lines_per_metre() * 4.0;
        assert!(
            (o.true_net as f64 - expected).abs() <= 1.5,
            "{o:?} vs {expected}"
        );
        assert_eq!(o.invalid, 0);
    }
}

/// A profile of the given kind around speed `v` (m/s) over `t_run` s, and
/// its peak speed (m/s). `frac` in [-1, 1] scales the acceleration: the
/// speed changes by `2 frac` m/s over the run (through zero, a reversal,
/// when it opposes `v` strongly enough).
fn profile_case(kind: u8, v: f64, frac: f64, s0: f64, t_run: f64) -> (Profile, f64) {
    match kind {
        0 => (constant(v, s0), v.abs()),
        1 => {
            let a = 2.0 * frac / t_run;
            (accelerating(v, a, s0), v.abs().max((v + a * t_run).abs()))
        }
        2 => {
            // Two full back-and-forth cycles, peak speed |v|.
            let freq = 2.0 / t_run;
            (
                reversing(v.abs() / (2.0 * core::f64::consts::PI * freq), freq, s0),
                v.abs(),
            )
        }
        _ => {
            let j = 0.3 * v.abs();
            (
                jittered(v, vec![(j, 37.0, 0.3), (0.5 * j, 211.0, 1.1)], s0),
                1.5 * v.abs(),
            )
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Decoded counts equal the true edge counts for constant, accelerating
    /// (and reversing through zero), back-and-forth and jittered motion over
    /// 0.01 to 2 m/s, with phase and duty-cycle errors and glitches; glitches
    /// are counted (two invalid transitions each: out and back) and never
    /// counted as motion.
    #[test]
    fn decoded_counts_are_exact(
        enc in channel_errors(),
        kind in 0u8..4,
        speed in (-2.0f64..0.31).prop_map(|e| 10f64.powf(e)),
        backwards in any::<bool>(),
        frac in -1.0f64..1.0,
        s0 in 0.0f64..0.01,
        glitch_prob in prop_oneof![Just(0.0), 1e-4f64..0.05],
        seed in any::<u64>(),
        start in prop_oneof![Just(0u32), 0u32..(1 << PAPER_BITS), Just((1 << PAPER_BITS) - 3)],
    ) {
        let v = if backwards { -speed } else { speed };
        // Long enough for ~500 edges, 50 ms to 1 s.
        let t_run = (500.0 / (speed * 4.0 * enc.lines_per_metre())).clamp(0.05, 1.0);
        let (profile, v_max) = profile_case(kind, v, frac, s0, t_run);
        let hz = sample_hz(&enc, v_max, 3.0).max(20_000.0);
        let wave = Waveform::new(enc, profile, hz);
        let o = decode_wave(&wave, (t_run * hz) as u64, glitch_prob, seed, start);
        assert_exact(&o);
        if glitch_prob > 0.01 {
            prop_assert!(o.glitches > 0);
        }
    }
}

#[test]
fn many_glitches_and_reversals_at_the_wrap() {
    // 2 s back and forth across the 20-bit wrap with 10 deg phase error,
    // 45 % / 55 % duty and 1 % of isolated samples glitched.
    let enc = EncoderModel::with_errors(10.0, 0.45, 0.55);
    let wave = Waveform::new(enc, reversing(0.2, 1.0, 0.0), sample_hz(&enc, 1.3, 3.0));
    let n = (2.0 * wave.sample_hz) as u64;
    let o = decode_wave(&wave, n, 0.01, 42, (1 << PAPER_BITS) - 500);
    assert_exact(&o);
    assert!(o.glitches > 300, "{o:?}");
    assert!(o.true_edges > 10_000, "{o:?}");
    eprintln!(
        "reversing 2 s: {} true edges, net {}, {} glitches -> {} invalid transitions, 0 counted",
        o.true_edges, o.true_net, o.glitches, o.invalid
    );
}

#[test]
fn counter_wraps_at_20_bits_with_exact_differences() {
    let mut c = Counter::paper();
    assert_eq!(c.bits(), 20);
    assert_eq!(c.mask(), 0xF_FFFF);
    c.set((1 << 20) - 2);
    let before = c.value();
    for _ in 0..5 {
        c.step(Direction::Forward);
    }
    assert_eq!(c.value(), 3);
    assert_eq!(c.since(before), 5);
    assert_eq!(wrapping_diff(before, c.value(), 20), -5);
    for _ in 0..10 {
        c.step(Direction::Reverse);
    }
    assert_eq!(c.value(), (1 << 20) - 7);
    assert_eq!(c.since(before), -5);
    // The extremes of the signed range [-2^19, 2^19).
    assert_eq!(wrapping_diff((1 << 19) - 1, 0, 20), (1 << 19) - 1);
    assert_eq!(wrapping_diff(1 << 19, 0, 20), -(1 << 19));
    assert_eq!(wrapping_diff(0, 1 << 19, 20), -(1 << 19));
    // Bits above the width are ignored.
    assert_eq!(wrapping_diff(0xFFF0_0005, 0x0000_0002, 20), 3);
    // Setting drops bits above the width.
    c.set(u32::MAX);
    assert_eq!(c.value(), 0xF_FFFF);
    c.reset();
    assert_eq!(c.value(), 0);
    assert_eq!(Counter::default(), Counter::paper());
}

#[test]
fn counter_widths_are_validated() {
    assert_eq!(
        Counter::new(0),
        Err(Error::InvalidParameter("counter width must be 1..=32 bits"))
    );
    assert!(Counter::new(33).is_err());
    for bits in [1, 8, 16, 20, 31, 32] {
        let c = Counter::new(bits).unwrap();
        assert_eq!(c.bits(), bits);
        assert_eq!(u64::from(c.mask()), (1u64 << bits) - 1);
    }
}

proptest! {
    /// A random walk of a 20-bit counter: every difference between two
    /// readings equals the true (unwrapped) motion between them, whenever
    /// that motion is within [-2^19, 2^19).
    #[test]
    fn counter_differences_across_the_wrap_are_exact(
        start in prop_oneof![0u32..(1 << 20), Just(0u32), Just((1 << 20) - 1)],
        steps in prop::collection::vec(-300_000i32..300_000, 1..40),
    ) {
        let mut c = Counter::paper();
        c.set(start);
        let mut truth = i64::from(start);
        let mut history = vec![(c.value(), truth)];
        for d in steps {
            c.add(d);
            truth += i64::from(d);
            prop_assert_eq!(i64::from(c.value()), truth.rem_euclid(1 << 20));
            history.push((c.value(), truth));
        }
        for &(v0, t0) in &history {
            for &(v1, t1) in &history {
                let motion = t1 - t0;
                if (-(1 << 19)..(1 << 19)).contains(&motion) {
                    prop_assert_eq!(i64::from(wrapping_diff(v1, v0, 20)), motion);
                }
            }
        }
    }

    /// Any width 1..=32: the difference is the true difference modulo 2^bits,
    /// mapped into [-2^(bits-1), 2^(bits-1)).
    #[test]
    fn wrapping_diff_matches_a_wide_reference(
        bits in 1u32..=32,
        later in any::<u32>(),
        earlier in any::<u32>(),
    ) {
        let m = 1i64 << bits;
        let d = (i64::from(later) - i64::from(earlier)).rem_euclid(m);
        let expected = if d >= m / 2 { d - m } else { d };
        prop_assert_eq!(i64::from(wrapping_diff(later, earlier, bits)), expected);
    }
}

/// A scripted source that fails on demand.
struct Script {
    levels: Vec<Result<(bool, bool), &'static str>>,
}

impl EncoderSource for Script {
    type Error = &'static str;
    fn sample(&mut self) -> Result<(bool, bool), Self::Error> {
        self.levels.remove(0)
    }
}

#[test]
fn polling_a_source_passes_its_error_and_keeps_the_decoder() {
    let mut src = Script {
        levels: vec![Ok((true, false)), Err("bus fault"), Ok((true, true))],
    };
    let mut dec = QuadratureDecoder::new(false, false, Counter::paper());
    assert_eq!(
        dec.poll(&mut src),
        Ok(Transition::Count(Direction::Forward))
    );
    let before = dec;
    assert_eq!(dec.poll(&mut &mut src), Err("bus fault"));
    assert_eq!(dec, before);
    assert_eq!(
        dec.poll(&mut src),
        Ok(Transition::Count(Direction::Forward))
    );
    assert_eq!(dec.counter().value(), 2);
}

#[test]
fn invalid_transition_count_can_be_cleared() {
    let mut dec = QuadratureDecoder::new(false, false, Counter::paper());
    assert_eq!(dec.update(true, true), Transition::Invalid);
    assert_eq!(dec.update(false, false), Transition::Invalid);
    assert_eq!(dec.invalid_transitions(), 2);
    assert_eq!(dec.counter().value(), 0);
    dec.clear_invalid_transitions();
    assert_eq!(dec.invalid_transitions(), 0);
    dec.counter_mut().set(17);
    assert_eq!(dec.counter().value(), 17);
    assert_eq!(
        format!("{}", Error::InvalidTransition),
        "invalid quadrature transition: both channels changed at once"
    );
}
