//! Windowed NIS consistency monitoring.
//!
//! For a consistent filter the normalised innovation squared
//! `NIS = y^T S^-1 y` of each correction (innovation `y = z - h(X-)`,
//! innovation covariance `S = H P- H^T + V R V^T`, spec
//! `shared/spec/MODELS.md` section 1) is dimensionless and chi-square
//! distributed with `m` degrees of freedom, `m` the measurement dimension.
//! Innovations of different steps are independent, so the sum of the NIS over
//! a window of `n` corrections is chi-square with `sum(m)` degrees of freedom.
//! The window's mean NIS is therefore tested against the two-sided interval
//! `[chi2_{sum m}(alpha/2) / n, chi2_{sum m}(1 - alpha/2) / n]`,
//! `alpha = 1 - confidence` (the classical NIS test of Bar-Shalom et al.).

use core::fmt;

use crate::{Error, chi2};

/// Outcome of a windowed NIS consistency test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Verdict {
    /// The window does not yet hold its full `W` samples: no verdict.
    Insufficient,
    /// The mean NIS lies inside the two-sided chi-square interval.
    Consistent,
    /// The mean NIS is above the interval: innovations are larger than the
    /// filter's innovation covariance `S` claims, i.e. the covariance (`P`,
    /// `Q` or `R`) is too small and the filter is over-confident.
    OverConfident,
    /// The mean NIS is below the interval: innovations are smaller than `S`
    /// claims, i.e. the covariance is too large (the filter is
    /// under-confident, e.g. `Q` or `R` over-estimated).
    UnderConfident,
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Verdict::Insufficient => "insufficient data",
            Verdict::Consistent => "consistent",
            Verdict::OverConfident => "over-confident (covariance too small)",
            Verdict::UnderConfident => "under-confident (covariance too large)",
        })
    }
}

/// Result of [`ConsistencyMonitor::assess`]. All NIS quantities are
/// dimensionless.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Consistency {
    /// Number of samples in the window (`<= W`).
    pub samples: usize,
    /// Mean NIS over the window (NaN if the window is empty).
    pub mean_nis: f64,
    /// Mean degrees of freedom (measurement dimension) over the window: the
    /// expected value of `mean_nis` for a consistent filter (NaN if empty).
    pub mean_dof: f64,
    /// Lower bound of the acceptance interval for `mean_nis`:
    /// `chi2_{sum dof}(alpha/2) / samples` (NaN if empty).
    pub lower: f64,
    /// Upper bound of the acceptance interval for `mean_nis`:
    /// `chi2_{sum dof}(1 - alpha/2) / samples` (NaN if empty).
    pub upper: f64,
    /// The verdict; [`Verdict::Insufficient`] until the window is full (the
    /// mean and bounds of a partial window are still reported).
    pub verdict: Verdict,
}

/// A windowed NIS consistency monitor over the last `W` corrections.
///
/// Keeps a ring buffer of the last `W` `(nis, dof)` samples in fixed arrays
/// (no allocation); [`assess`](Self::assess) recomputes the window's sums
/// exactly from the buffer (compensated summation for the NIS, integer sum for
/// the degrees of freedom), so there is no drift however long the monitor
/// runs. `W` must be at least 1 (checked at compile time).
///
/// ```
/// # use locus_core::{ConsistencyMonitor, Verdict};
/// let mut monitor = ConsistencyMonitor::<4>::new(0.95).unwrap();
/// for nis in [1.7, 2.4, 0.9, 2.2] {
///     monitor.push(nis, 2);
/// }
/// assert_eq!(monitor.assess().verdict, Verdict::Consistent);
/// ```
#[derive(Debug, Clone)]
pub struct ConsistencyMonitor<const W: usize> {
    confidence: f64,
    nis: [f64; W],
    dof: [u32; W],
    /// Index the next sample is written to.
    head: usize,
    len: usize,
    rejected_non_finite: u64,
    rejected_invalid: u64,
}

impl<const W: usize> ConsistencyMonitor<W> {
    /// Creates an empty monitor with a two-sided test at `confidence`: e.g.
    /// `0.95` puts the bounds at the 2.5 % and 97.5 % chi-square quantiles.
    ///
    /// # Errors
    ///
    /// [`Error::InvalidParameter`] unless `confidence` is finite and strictly
    /// inside `(0, 1)`.
    pub fn new(confidence: f64) -> Result<Self, Error> {
        const { assert!(W > 0, "ConsistencyMonitor window W must be at least 1") };
        if !(confidence > 0.0 && confidence < 1.0) {
            return Err(Error::InvalidParameter(
                "consistency confidence must be finite and strictly inside (0, 1)",
            ));
        }
        Ok(Self {
            confidence,
            nis: [0.0; W],
            dof: [0; W],
            head: 0,
            len: 0,
            rejected_non_finite: 0,
            rejected_invalid: 0,
        })
    }

    /// The two-sided confidence level of the test, in `(0, 1)`.
    #[must_use]
    pub fn confidence(&self) -> f64 {
        self.confidence
    }

    /// The window length `W` (number of samples a verdict needs).
    #[must_use]
    pub fn capacity(&self) -> usize {
        W
    }

    /// Records the NIS (dimensionless `y^T S^-1 y`) of one correction with
    /// `dof` measurement components, evicting the oldest sample once the
    /// window is full.
    ///
    /// A non-finite `nis` (NaN or infinite) is not stored; it is counted in
    /// [`rejected_non_finite`](Self::rejected_non_finite). A sample with
    /// `dof == 0` or a negative `nis` (impossible for a positive definite `S`)
    /// is not stored either and is counted in
    /// [`rejected_invalid`](Self::rejected_invalid).
    pub fn push(&mut self, nis: f64, dof: u32) {
        if !nis.is_finite() {
            self.rejected_non_finite = self.rejected_non_finite.saturating_add(1);
            return;
        }
        if dof == 0 || nis < 0.0 {
            self.rejected_invalid = self.rejected_invalid.saturating_add(1);
            return;
        }
        self.nis[self.head] = nis;
        self.dof[self.head] = dof;
        self.head = if self.head + 1 == W { 0 } else { self.head + 1 };
        if self.len < W {
            self.len += 1;
        }
    }

    /// Number of samples currently in the window (`0..=W`).
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the window holds no samples.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether the window holds `W` samples (a verdict is available).
    #[must_use]
    pub fn is_full(&self) -> bool {
        self.len == W
    }

    /// Number of pushed samples discarded because their NIS was NaN or
    /// infinite (since creation or the last [`clear`](Self::clear)).
    #[must_use]
    pub fn rejected_non_finite(&self) -> u64 {
        self.rejected_non_finite
    }

    /// Number of pushed samples discarded because `dof == 0` or the NIS was
    /// negative (since creation or the last [`clear`](Self::clear)).
    #[must_use]
    pub fn rejected_invalid(&self) -> u64 {
        self.rejected_invalid
    }

    /// Empties the window and resets the rejection counters; the confidence
    /// is kept.
    pub fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
        self.rejected_non_finite = 0;
        self.rejected_invalid = 0;
    }

    /// Tests the window: the mean NIS against the two-sided chi-square
    /// interval for its total degrees of freedom.
    ///
    /// The verdict is [`Verdict::Insufficient`] until the window holds `W`
    /// samples; the mean and the bounds are reported for a partial window
    /// too (all NaN when empty). Costs `O(W)` plus two chi-square quantiles.
    #[must_use]
    pub fn assess(&self) -> Consistency {
        let n = self.len;
        if n == 0 {
            return Consistency {
                samples: 0,
                mean_nis: f64::NAN,
                mean_dof: f64::NAN,
                lower: f64::NAN,
                upper: f64::NAN,
                verdict: Verdict::Insufficient,
            };
        }
        // The occupied slots are 0..n (before the first wrap the window fills
        // from index 0; afterwards every slot is occupied). Order is
        // irrelevant for the sums.
        let (sum_nis, sum_dof) = window_sums(&self.nis[..n], &self.dof[..n]);
        let nf = n as f64;
        let dof_total = u32::try_from(sum_dof).unwrap_or(u32::MAX);
        let bound = |p: f64| chi2::quantile(p, dof_total).map_or(f64::NAN, |q| q / nf);
        let lower = bound(0.5 * (1.0 - self.confidence));
        let upper = bound(0.5 * (1.0 + self.confidence));
        let mean_nis = sum_nis / nf;
        let verdict = if n < W {
            Verdict::Insufficient
        } else if mean_nis > upper {
            Verdict::OverConfident
        } else if mean_nis < lower {
            Verdict::UnderConfident
        } else {
            Verdict::Consistent
        };
        Consistency {
            samples: n,
            mean_nis,
            mean_dof: sum_dof as f64 / nf,
            lower,
            upper,
            verdict,
        }
    }
}

/// Sums of the window: NIS by Neumaier-compensated summation, dof exactly.
fn window_sums(nis: &[f64], dof: &[u32]) -> (f64, u64) {
    let mut sum = 0.0_f64;
    let mut compensation = 0.0_f64;
    for &v in nis {
        let t = sum + v;
        if sum.abs() >= v.abs() {
            compensation += (sum - t) + v;
        } else {
            compensation += (v - t) + sum;
        }
        sum = t;
    }
    let dof_sum = dof.iter().map(|&d| u64::from(d)).sum();
    (sum + compensation, dof_sum)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::fmt::Write;

    /// xorshift64* generator with Box–Muller normals (deterministic).
    struct Rng {
        state: u64,
        spare: Option<f64>,
    }

    impl Rng {
        fn new(seed: u64) -> Self {
            Self {
                state: seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1,
                spare: None,
            }
        }

        fn next_u64(&mut self) -> u64 {
            let mut x = self.state;
            x ^= x >> 12;
            x ^= x << 25;
            x ^= x >> 27;
            self.state = x;
            x.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }

        /// Uniform in (0, 1).
        fn uniform(&mut self) -> f64 {
            ((self.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
        }

        fn normal(&mut self) -> f64 {
            if let Some(z) = self.spare.take() {
                return z;
            }
            let r = libm::sqrt(-2.0 * libm::log(self.uniform()));
            let theta = 2.0 * core::f64::consts::PI * self.uniform();
            self.spare = Some(r * libm::sin(theta));
            r * libm::cos(theta)
        }

        /// A chi-square sample with `dof` degrees of freedom.
        fn chi2(&mut self, dof: u32) -> f64 {
            (0..dof)
                .map(|_| {
                    let z = self.normal();
                    z * z
                })
                .sum()
        }
    }

    /// Runs `windows` independent full windows of true chi-square NIS samples
    /// (dof cycling through 1..=4) scaled by `scale`; returns the verdict counts
    /// `[consistent, over, under]`.
    fn run<const W: usize>(scale: f64, windows: usize, seed: u64) -> [usize; 3] {
        let mut rng = Rng::new(seed);
        let mut counts = [0usize; 3];
        let mut monitor = ConsistencyMonitor::<W>::new(0.95).unwrap();
        for _ in 0..windows {
            monitor.clear();
            for i in 0..W {
                let dof = (i % 4) as u32 + 1;
                monitor.push(scale * rng.chi2(dof), dof);
            }
            let c = monitor.assess();
            assert_eq!(c.samples, W);
            assert!(c.lower < c.mean_dof && c.mean_dof < c.upper);
            match c.verdict {
                Verdict::Consistent => counts[0] += 1,
                Verdict::OverConfident => counts[1] += 1,
                Verdict::UnderConfident => counts[2] += 1,
                Verdict::Insufficient => panic!("full window gave Insufficient"),
            }
        }
        counts
    }

    #[test]
    fn rng_produces_standard_normals() {
        let mut rng = Rng::new(7);
        let n = 200_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let z = rng.normal();
            s1 += z;
            s2 += z * z;
        }
        let mean = s1 / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!((var - 1.0).abs() < 0.02, "variance {var}");
    }

    #[test]
    fn consistent_filter_is_mostly_consistent() {
        let windows = 400;
        let [ok, over, under] = run::<50>(1.0, windows, 1);
        // Expected 95 % consistent, 2.5 % each side.
        assert!(ok * 10 > windows * 9, "only {ok}/{windows} consistent");
        assert!(
            over < windows / 10 && under < windows / 10,
            "over {over}, under {under}"
        );
        let [ok, _, _] = run::<10>(1.0, windows, 2);
        assert!(
            ok * 10 > windows * 9,
            "W = 10: only {ok}/{windows} consistent"
        );
    }

    #[test]
    fn scaled_nis_is_detected() {
        assert_eq!(
            run::<20>(3.0, 200, 3),
            [0, 200, 0],
            "NIS x 3 must be over-confident"
        );
        assert_eq!(
            run::<20>(0.3, 200, 4),
            [0, 0, 200],
            "NIS x 0.3 must be under-confident"
        );
    }

    #[test]
    fn bounds_and_ring_buffer() {
        let mut m = ConsistencyMonitor::<3>::new(0.95).unwrap();
        assert!(m.is_empty() && !m.is_full() && m.capacity() == 3);
        assert_eq!(m.len(), 0);
        let c = m.assess();
        assert_eq!(c.samples, 0);
        assert_eq!(c.verdict, Verdict::Insufficient);
        assert!(c.mean_nis.is_nan() && c.lower.is_nan() && c.upper.is_nan());

        m.push(1.0, 2);
        m.push(2.0, 2);
        let c = m.assess();
        assert_eq!((c.samples, c.verdict), (2, Verdict::Insufficient));
        assert_eq!(c.mean_nis, 1.5);
        assert_eq!(c.mean_dof, 2.0);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-13 * b;
        assert!(close(c.lower, chi2::quantile(0.025, 4).unwrap() / 2.0));
        assert!(close(c.upper, chi2::quantile(0.975, 4).unwrap() / 2.0));

        m.push(3.0, 1);
        assert!(m.is_full());
        let c = m.assess();
        assert_eq!(c.verdict, Verdict::Consistent);
        assert_eq!(c.mean_nis, 2.0);
        assert_eq!(c.mean_dof, 5.0 / 3.0);

        // Evicts 1.0 (dof 2) and 2.0 (dof 2): window is {3.0/1, 40.0/3, 50.0/3}.
        m.push(40.0, 3);
        m.push(50.0, 3);
        assert_eq!(m.len(), 3);
        let c = m.assess();
        assert_eq!(c.mean_nis, 31.0);
        assert_eq!(c.mean_dof, 7.0 / 3.0);
        assert!(close(c.upper, chi2::quantile(0.975, 7).unwrap() / 3.0));
        assert_eq!(c.verdict, Verdict::OverConfident);

        for _ in 0..3 {
            m.push(1e-6, 3);
        }
        assert_eq!(m.assess().verdict, Verdict::UnderConfident);

        // Long run: sums are recomputed, no drift after huge values leave.
        m.push(1e300, 1);
        for _ in 0..10 {
            m.push(0.5, 1);
        }
        assert_eq!(m.assess().mean_nis, 0.5);

        m.clear();
        assert!(m.is_empty());
        assert_eq!(m.assess().verdict, Verdict::Insufficient);
    }

    #[test]
    fn rejected_samples_are_counted_not_stored() {
        let mut m = ConsistencyMonitor::<2>::new(0.9).unwrap();
        m.push(f64::NAN, 2);
        m.push(f64::INFINITY, 2);
        m.push(f64::NEG_INFINITY, 1);
        m.push(1.0, 0);
        m.push(-0.5, 2);
        assert!(m.is_empty());
        assert_eq!(m.rejected_non_finite(), 3);
        assert_eq!(m.rejected_invalid(), 2);
        m.push(2.0, 2);
        m.push(f64::NAN, 2);
        m.push(0.0, 2);
        assert!(m.is_full());
        let c = m.assess();
        assert_eq!(c.mean_nis, 1.0);
        assert!(!c.mean_nis.is_nan());
        assert_eq!(m.rejected_non_finite(), 4);
        m.clear();
        assert_eq!((m.rejected_non_finite(), m.rejected_invalid()), (0, 0));
        assert_eq!(m.confidence(), 0.9);
    }

    #[test]
    fn invalid_confidence() {
        for c in [0.0, 1.0, -1.0, 2.0, f64::NAN, f64::NEG_INFINITY] {
            assert!(matches!(
                ConsistencyMonitor::<5>::new(c),
                Err(Error::InvalidParameter(_))
            ));
        }
    }

    #[test]
    fn wider_confidence_gives_wider_bounds() {
        let mut a = ConsistencyMonitor::<8>::new(0.9).unwrap();
        let mut b = ConsistencyMonitor::<8>::new(0.99).unwrap();
        for i in 0..8 {
            a.push(1.0 + i as f64 * 0.1, 2);
            b.push(1.0 + i as f64 * 0.1, 2);
        }
        let (ca, cb) = (a.assess(), b.assess());
        assert!(cb.lower < ca.lower && ca.upper < cb.upper);
        assert!(ca.lower < 2.0 && 2.0 < ca.upper);
    }

    #[test]
    fn verdict_display() {
        struct Buf {
            bytes: [u8; 64],
            len: usize,
        }
        impl Write for Buf {
            fn write_str(&mut self, s: &str) -> fmt::Result {
                let end = self.len + s.len();
                self.bytes
                    .get_mut(self.len..end)
                    .ok_or(fmt::Error)?
                    .copy_from_slice(s.as_bytes());
                self.len = end;
                Ok(())
            }
        }
        let cases = [
            (Verdict::Insufficient, "insufficient data"),
            (Verdict::Consistent, "consistent"),
            (
                Verdict::OverConfident,
                "over-confident (covariance too small)",
            ),
            (
                Verdict::UnderConfident,
                "under-confident (covariance too large)",
            ),
        ];
        for (v, text) in cases {
            let mut buf = Buf {
                bytes: [0; 64],
                len: 0,
            };
            write!(buf, "{v}").unwrap();
            assert_eq!(&buf.bytes[..buf.len], text.as_bytes());
        }
    }
}
