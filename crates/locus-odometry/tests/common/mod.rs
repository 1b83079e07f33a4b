//! Shared helpers of the encoder tests: a quadrature waveform generator with
//! phase error between A and B, duty-cycle error and injected glitches, and
//! wheel-travel profiles (constant, accelerating, reversing, jittered).
//!
//! The generator works in encoder-shaft position `theta`, in **line periods**
//! (one line = one full cycle of A and B = 4 x4 counts). Within a line the
//! four edges sit at
//!
//! ```text
//! A rises 0,  B rises 0.25 + phase_error,  A falls duty_a,
//! B falls 0.25 + phase_error + duty_b      (all modulo 1)
//! ```
//!
//! and the true x4 count at `theta` is `4 floor(theta) + (edges <= frac)`.
//! The sampled levels and the true count are computed from the same two
//! integers, so they agree to the last bit whatever the rounding.
#![allow(dead_code)]

use core::f64::consts::PI;

/// An encoder with imperfect channels on a wheel.
#[derive(Debug, Clone, Copy)]
pub struct EncoderModel {
    /// Lines per encoder-shaft revolution `N`.
    pub lines: u32,
    /// Encoder-shaft revolutions per wheel revolution `G`.
    pub gear: f64,
    /// Wheel radius `R`, m.
    pub radius: f64,
    /// Extra lag of B behind its nominal quarter line, line periods
    /// (10 deg = 10/360).
    pub phase_error: f64,
    /// Fraction of a line period A is high (ideal 0.5).
    pub duty_a: f64,
    /// Fraction of a line period B is high (ideal 0.5).
    pub duty_b: f64,
}

impl EncoderModel {
    /// The spec's \[assumed\] encoder (500 lines, G = 1, R = 0.05 m), ideal
    /// channels.
    pub fn ideal() -> Self {
        Self {
            lines: 500,
            gear: 1.0,
            radius: 0.05,
            phase_error: 0.0,
            duty_a: 0.5,
            duty_b: 0.5,
        }
    }

    /// The \[assumed\] encoder with a phase error (degrees of a line period)
    /// and the two duty cycles.
    pub fn with_errors(phase_error_deg: f64, duty_a: f64, duty_b: f64) -> Self {
        let e = Self {
            phase_error: phase_error_deg / 360.0,
            duty_a,
            duty_b,
            ..Self::ideal()
        };
        let edges = e.edges();
        assert!(
            edges.windows(2).all(|w| w[0] < w[1]) && edges[3] < 1.0,
            "edges out of order: {edges:?}"
        );
        e
    }

    /// Edge positions within a line period, increasing: A rise, B rise,
    /// A fall, B fall.
    pub fn edges(&self) -> [f64; 4] {
        let b = 0.25 + self.phase_error;
        [0.0, b, self.duty_a, b + self.duty_b]
    }

    /// The smallest distance between two successive edges, line periods.
    pub fn min_edge_gap(&self) -> f64 {
        let e = self.edges();
        (0..4)
            .map(|i| if i < 3 { e[i + 1] - e[i] } else { 1.0 - e[3] })
            .fold(f64::INFINITY, f64::min)
    }

    /// Spread of the edges' displacements from their nominal quarter-line
    /// positions, counts: the pulse-mode count error is below `1 + spread`.
    pub fn spread_counts(&self) -> f64 {
        let d: Vec<f64> = self
            .edges()
            .iter()
            .enumerate()
            .map(|(i, &e)| 4.0 * e - i as f64)
            .collect();
        d.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - d.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Line periods per metre of wheel travel, `N G / (2 pi R)`.
    pub fn lines_per_metre(&self) -> f64 {
        f64::from(self.lines) * self.gear / (2.0 * PI * self.radius)
    }

    /// Wheel travel per x4 count, m: `pi R / (2 N G)`.
    pub fn metres_per_count(&self) -> f64 {
        1.0 / (4.0 * self.lines_per_metre())
    }

    /// `(floor(theta), edges at or before frac(theta))`, the latter in 1..=4.
    fn cell(&self, theta: f64) -> (i64, i64) {
        let whole = theta.floor();
        let frac = theta - whole;
        let k = self.edges().iter().filter(|&&e| e <= frac).count() as i64;
        (whole as i64, k.max(1))
    }

    /// The true x4 count at shaft position `theta` (line periods).
    pub fn true_count(&self, theta: f64) -> i64 {
        let (whole, k) = self.cell(theta);
        4 * whole + k
    }

    /// The levels `(A, B)` at shaft position `theta`.
    pub fn levels(&self, theta: f64) -> (bool, bool) {
        match self.cell(theta).1 {
            1 => (true, false),
            2 => (true, true),
            3 => (false, true),
            _ => (false, false),
        }
    }
}

/// Wheel travel (m) as a function of time (s).
pub type Profile = Box<dyn Fn(f64) -> f64>;

/// Constant speed `v` (m/s) from `s0` (m).
pub fn constant(v: f64, s0: f64) -> Profile {
    Box::new(move |t| s0 + v * t)
}

/// Constant acceleration `a` (m/s^2) from speed `v0` (m/s) at `s0` (m):
/// reverses at `t = -v0 / a` if the signs differ.
pub fn accelerating(v0: f64, a: f64, s0: f64) -> Profile {
    Box::new(move |t| s0 + v0 * t + 0.5 * a * t * t)
}

/// Back and forth: `s0 + amplitude sin(2 pi freq t)`, reversing twice per
/// period (peak speed `2 pi freq amplitude`).
pub fn reversing(amplitude: f64, freq: f64, s0: f64) -> Profile {
    Box::new(move |t| s0 + amplitude * (2.0 * PI * freq * t).sin())
}

/// Speed `v0 + sum a_i sin(2 pi f_i t + p_i)` (m/s), integrated in closed
/// form; `jitter` holds `(a_i m/s, f_i Hz, p_i rad)`.
pub fn jittered(v0: f64, jitter: Vec<(f64, f64, f64)>, s0: f64) -> Profile {
    Box::new(move |t| {
        s0 + v0 * t
            + jitter
                .iter()
                .map(|&(a, f, p)| {
                    let w = 2.0 * PI * f;
                    a / w * (p.cos() - (w * t + p).cos())
                })
                .sum::<f64>()
    })
}

/// A sampled waveform: an encoder moved by a profile, sampled at
/// `sample_hz`; sample `k` is taken at `t = k / sample_hz`.
pub struct Waveform {
    /// The encoder.
    pub encoder: EncoderModel,
    /// Wheel travel, m, against time, s.
    pub profile: Profile,
    /// Sampling rate, Hz (in the speed tests also the reference clock: the
    /// sample index is the capture timer's tick).
    pub sample_hz: f64,
}

/// One generated sample.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    /// Index `k` (the tick).
    pub tick: u64,
    /// The levels handed to the decoder (inverted if `glitch`).
    pub levels: (bool, bool),
    /// The true x4 count at this instant.
    pub true_count: i64,
    /// Both levels were inverted in this sample only.
    pub glitch: bool,
}

impl Waveform {
    /// A waveform of `encoder` driven by `profile`, sampled at `sample_hz`.
    pub fn new(encoder: EncoderModel, profile: Profile, sample_hz: f64) -> Self {
        Self {
            encoder,
            profile,
            sample_hz,
        }
    }

    /// Time of sample `k`, s.
    pub fn time(&self, k: u64) -> f64 {
        k as f64 / self.sample_hz
    }

    /// Wheel travel at time `t`, m.
    pub fn travel(&self, t: f64) -> f64 {
        (self.profile)(t)
    }

    /// Shaft position at time `t`, line periods.
    pub fn theta(&self, t: f64) -> f64 {
        self.travel(t) * self.encoder.lines_per_metre()
    }

    /// The true count at time `t`.
    pub fn count_at(&self, t: f64) -> i64 {
        self.encoder.true_count(self.theta(t))
    }

    /// The instant in `((k-1)/fs, k/fs]` where the true count changed
    /// (an edge detected at sample `k`), by bisection to ~1e-15 s.
    pub fn edge_time(&self, k: u64) -> f64 {
        let (mut lo, mut hi) = (self.time(k - 1), self.time(k));
        let before = self.count_at(lo);
        assert_ne!(before, self.count_at(hi), "no edge at sample {k}");
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.count_at(mid) == before {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }

    /// Samples `0..n`, each isolated sample (no true edge from the previous
    /// to the next sample, previous sample not glitched) glitched with
    /// probability `glitch_prob` (seeded by `seed`).
    ///
    /// Panics if two true edges fall between two samples (the sampling is
    /// too slow for the speed: the true stream itself would hold an invalid
    /// transition).
    pub fn samples(&self, n: u64, glitch_prob: f64, seed: u64) -> Samples<'_> {
        Samples {
            wave: self,
            n,
            k: 0,
            prev: None,
            current: self.true_sample(0),
            rng: SplitMix64(seed),
            glitch_prob,
            last_glitch: false,
        }
    }

    fn true_sample(&self, k: u64) -> ((bool, bool), i64) {
        let theta = self.theta(self.time(k));
        (self.encoder.levels(theta), self.encoder.true_count(theta))
    }
}

/// The iterator of [`Waveform::samples`].
pub struct Samples<'a> {
    wave: &'a Waveform,
    n: u64,
    k: u64,
    prev: Option<i64>,
    current: ((bool, bool), i64),
    rng: SplitMix64,
    glitch_prob: f64,
    last_glitch: bool,
}

impl Iterator for Samples<'_> {
    type Item = Sample;

    fn next(&mut self) -> Option<Sample> {
        if self.k >= self.n {
            return None;
        }
        let k = self.k;
        let (levels, count) = self.current;
        let next = self.wave.true_sample(k + 1);
        if let Some(p) = self.prev {
            assert!(
                (count - p).abs() <= 1,
                "sampling too slow: {} edges between samples {} and {k}",
                (count - p).abs(),
                k - 1
            );
        }
        // A glitch needs a next sample to return from it (`s, !s, s`).
        let isolated =
            self.prev == Some(count) && next.1 == count && !self.last_glitch && k + 1 < self.n;
        let glitch = isolated && self.rng.unit() < self.glitch_prob;
        self.last_glitch = glitch;
        self.prev = Some(count);
        self.current = next;
        self.k += 1;
        Some(Sample {
            tick: k,
            levels: if glitch {
                (!levels.0, !levels.1)
            } else {
                levels
            },
            true_count: count,
            glitch,
        })
    }
}

/// A tiny deterministic generator (SplitMix64) for glitch placement.
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}
