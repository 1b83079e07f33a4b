//! A reference trajectory's own error, from its errors over relations
//! measured apart from it, and an estimator's consistency against such a
//! reference.
//!
//! A log's "truth" is often another estimator's output: the Intel lab's
//! corrected poses come from a SLAM back end. Judged against it, a filter's
//! 3-sigma shares count the reference's errors as the filter's. Where
//! relations measured apart from the reference exist (the Intel lab's
//! hand-verified ones, Kuemmerle et al. 2009), they say how large the
//! reference's errors are.
//!
//! Model: each reference pose is off by an error independent from pose to
//! pose, zero-mean, with a standard deviation `sigma_xy` on each of x and y
//! and `sigma_theta` on the heading. A relation's error (composed in SE(2),
//! [`crate::relations`]) is then, to first order, the difference of two
//! poses' errors, rotated into the first pose's frame: each of its
//! components has twice the variance of one pose's. The heading error
//! times the relation's length also enters its translation; on the Intel
//! lab's relations on scans (a median length of 6 cm) that term is below
//! a millimetre and is left out.
//!
//! The estimate is robust: the median absolute component over `sqrt(2)`
//! and over 0.6745 (the median of `|N(0, 1)|`), so that a few bad relations
//! do not inflate it. Every disagreement is counted as the reference's (the
//! relations' own errors are not known), so the result is an upper bound of
//! its error from pose to pose. An error shared by the poses a relation
//! joins (a map frame slowly bent) does not show in a relation; nor does it
//! count against a filter localising in a map built from those same poses.
//!
//! Units: m, rad.

use locus_core::nalgebra::{Matrix3, Vector3};

use crate::relations::{Relation, between};

/// Fewest relations the reference's error is estimated from.
pub const MIN_RELATIONS: usize = 10;

/// The median of `|N(0, 1)|`: a normal's median absolute deviation over
/// its standard deviation.
const MAD_PER_SIGMA: f64 = 0.674_489_750_196_081_7;

/// A reference trajectory's error at one pose ([module](self)), m and rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceError {
    /// Relations it was estimated from.
    pub relations: usize,
    /// Standard deviation of each of x and y, m.
    pub sigma_xy: f64,
    /// Standard deviation of the heading, rad.
    pub sigma_theta: f64,
}

impl ReferenceError {
    /// The reference's error as a covariance of `[x, y, theta]`.
    #[must_use]
    pub fn covariance(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::new(
            self.sigma_xy.powi(2),
            self.sigma_xy.powi(2),
            self.sigma_theta.powi(2),
        ))
    }
}

/// The error of the reference trajectory `pose` (the pose at an index,
/// `None` where it has none) from its relations whose ends fall on the
/// indices `ends` (as [`crate::relations::evaluate_at`] takes them), or
/// `None` with fewer than [`MIN_RELATIONS`] relations covered.
///
/// # Panics
/// If `ends` is not as long as `relations`.
#[must_use]
pub fn reference_error(
    relations: &[Relation],
    ends: &[Option<(usize, usize)>],
    mut pose: impl FnMut(usize) -> Option<[f64; 3]>,
) -> Option<ReferenceError> {
    assert_eq!(relations.len(), ends.len(), "one pair of ends per relation");
    let mut xy = Vec::new();
    let mut theta = Vec::new();
    for (r, e) in relations.iter().zip(ends) {
        let Some((i, j)) = *e else { continue };
        let (Some(a), Some(b)) = (pose(i), pose(j)) else {
            continue;
        };
        let e = between([r.dx, r.dy, r.dyaw], between(a, b));
        xy.extend([e[0].abs(), e[1].abs()]);
        theta.push(e[2].abs());
    }
    if theta.len() < MIN_RELATIONS {
        return None;
    }
    let sigma = |v: &mut Vec<f64>| median(v) / MAD_PER_SIGMA / core::f64::consts::SQRT_2;
    Some(ReferenceError {
        relations: theta.len(),
        sigma_xy: sigma(&mut xy),
        sigma_theta: sigma(&mut theta),
    })
}

/// The median of finite values (sorted in place), NaN for none.
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// An estimator's consistency with a reference trajectory at the poses
/// both have: the shares inside 3 sigma and the mean NEES, of the estimate
/// alone and with the reference's own error added to its covariance. NaN
/// where nothing was compared (or no reference error is known).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Consistency {
    /// Poses compared.
    pub compared: usize,
    /// Shares of x, y and heading errors inside 3 standard deviations of
    /// the estimate's own variance.
    pub within_3_sigma: [f64; 3],
    /// As [`Consistency::within_3_sigma`], of the estimate's variance plus
    /// the reference's.
    pub within_3_sigma_with_reference: [f64; 3],
    /// Mean NEES (3 dof) of the estimate's covariance.
    pub mean_nees: f64,
    /// Mean NEES (3 dof) of the estimate's covariance plus the
    /// reference's.
    pub mean_nees_with_reference: f64,
}

/// The [`Consistency`] of estimates `(pose, covariance)` against the
/// reference poses beside them (errors reference minus estimate, the
/// heading wrapped), with the reference's error `reference`.
#[must_use]
#[allow(clippy::cast_precision_loss)]
pub fn consistency(
    pairs: impl IntoIterator<Item = ([f64; 3], Matrix3<f64>, [f64; 3])>,
    reference: Option<&ReferenceError>,
) -> Consistency {
    let extra = reference.map(ReferenceError::covariance);
    let mut n = 0usize;
    let mut inside = [[0usize; 3]; 2];
    let mut nees = [0.0f64; 2];
    for (x, p, truth) in pairs {
        let e = Vector3::new(
            truth[0] - x[0],
            truth[1] - x[1],
            locus_core::wrap_angle(truth[2] - x[2]),
        );
        n += 1;
        for (k, cov) in [Some(p), extra.map(|r| p + r)].into_iter().enumerate() {
            let Some(cov) = cov else { continue };
            for i in 0..3 {
                inside[k][i] += usize::from(e[i].abs() <= 3.0 * cov[(i, i)].sqrt());
            }
            nees[k] += crate::nees(&e, &cov);
        }
    }
    let per = |v: f64| if n == 0 { f64::NAN } else { v / n as f64 };
    let with = |v: f64| if extra.is_some() { v } else { f64::NAN };
    Consistency {
        compared: n,
        within_3_sigma: inside[0].map(|c| per(c as f64)),
        within_3_sigma_with_reference: inside[1].map(|c| with(per(c as f64))),
        mean_nees: per(nees[0]),
        mean_nees_with_reference: with(per(nees[1])),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator of standard normal draws
    /// (Box-Muller over a 64-bit LCG).
    struct Normal(u64);

    impl Normal {
        fn uniform(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            #[allow(clippy::cast_precision_loss)]
            let u = (self.0 >> 11) as f64 / (1u64 << 53) as f64;
            u.max(f64::MIN_POSITIVE)
        }
        fn draw(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            (-2.0 * u.ln()).sqrt() * (core::f64::consts::TAU * v).cos()
        }
    }

    /// A true path, short exact relations between neighbours, and a
    /// reference off the truth by `sigma_xy`, `sigma_theta` at each pose.
    fn reference(
        n: usize,
        sigma_xy: f64,
        sigma_theta: f64,
    ) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<Relation>) {
        let mut g = Normal(7);
        #[allow(clippy::cast_precision_loss)]
        let truth: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                let t = i as f64 * 0.05;
                [t.cos() * 3.0, t.sin() * 3.0, t + 1.5]
            })
            .collect();
        let reference = truth
            .iter()
            .map(|p| {
                [
                    p[0] + sigma_xy * g.draw(),
                    p[1] + sigma_xy * g.draw(),
                    p[2] + sigma_theta * g.draw(),
                ]
            })
            .collect();
        #[allow(clippy::cast_precision_loss)]
        let relations = (1..n)
            .map(|i| {
                let d = between(truth[i - 1], truth[i]);
                Relation {
                    t1: (i - 1) as f64,
                    t2: i as f64,
                    dx: d[0],
                    dy: d[1],
                    dyaw: d[2],
                    line: 0,
                }
            })
            .collect();
        (truth, reference, relations)
    }

    #[test]
    fn a_reference_error_is_recovered_from_exact_relations() {
        let (_, reference, relations) = reference(4001, 0.02, 0.005);
        let ends: Vec<_> = (1..4001).map(|i| Some((i - 1, i))).collect();
        let e = reference_error(&relations, &ends, |i| reference.get(i).copied()).unwrap();
        assert_eq!(e.relations, 4000);
        // 4000 relations: the MAD's own spread is about 2.5 % (x, y: 8000
        // components, 1.8 %).
        assert!((e.sigma_xy / 0.02 - 1.0).abs() < 0.05, "{e:?}");
        assert!((e.sigma_theta / 0.005 - 1.0).abs() < 0.08, "{e:?}");
        // A few wild relations barely move it.
        let mut wild = relations.clone();
        for r in wild.iter_mut().step_by(50) {
            r.dx += 1.0;
            r.dyaw += 0.5;
        }
        let w = reference_error(&wild, &ends, |i| reference.get(i).copied()).unwrap();
        assert!((w.sigma_xy / e.sigma_xy - 1.0).abs() < 0.05, "{w:?}");
        assert!((w.sigma_theta / e.sigma_theta - 1.0).abs() < 0.05, "{w:?}");
        // Too few relations: no estimate.
        assert!(
            reference_error(&relations[..9], &ends[..9], |i| reference.get(i).copied()).is_none()
        );
    }

    #[test]
    fn an_honest_estimate_against_a_noisy_reference_is_consistent_only_with_its_error() {
        // An estimate whose error is exactly its covariance's (0.01 m,
        // 0.004 rad), judged against a reference wrong by more (0.02 m,
        // 0.008 rad): alone it looks overconfident; with the reference's
        // error estimated from the relations, it is inside 3 sigma 99.7 %.
        let n = 4001;
        let (truth, reference, relations) = reference(n, 0.02, 0.008);
        let ends: Vec<_> = (1..n).map(|i| Some((i - 1, i))).collect();
        let r = reference_error(&relations, &ends, |i| reference.get(i).copied()).unwrap();
        let mut g = Normal(11);
        let p = Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 1.6e-5));
        let pairs: Vec<_> = truth
            .iter()
            .zip(&reference)
            .map(|(t, refp)| {
                let x = [
                    t[0] + 0.01 * g.draw(),
                    t[1] + 0.01 * g.draw(),
                    t[2] + 0.004 * g.draw(),
                ];
                (x, p, *refp)
            })
            .collect();
        let c = consistency(pairs.iter().copied(), Some(&r));
        assert_eq!(c.compared, n);
        for k in 0..3 {
            assert!(c.within_3_sigma[k] < 0.9, "{c:?}");
            assert!(c.within_3_sigma_with_reference[k] > 0.99, "{c:?}");
        }
        assert!(c.mean_nees > 6.0, "{c:?}");
        assert!((c.mean_nees_with_reference - 3.0).abs() < 0.3, "{c:?}");
        // Against the truth itself the estimate alone is consistent.
        let exact: Vec<_> = pairs
            .iter()
            .zip(&truth)
            .map(|(&(x, p, _), t)| (x, p, *t))
            .collect();
        let c = consistency(exact, None);
        assert!(c.within_3_sigma.iter().all(|&s| s > 0.99), "{c:?}");
        assert!(c.within_3_sigma_with_reference[0].is_nan() && c.mean_nees_with_reference.is_nan());
        assert!(consistency([], None).mean_nees.is_nan());
    }
}
