//! The extended Rauch-Tung-Striebel smoother over the replay's forward pass
//! (Rauch, Tung and Striebel, "Maximum likelihood estimates of linear
//! dynamic systems", AIAA Journal 3(8), 1965; extended form as in Sarkka,
//! "Bayesian Filtering and Smoothing", 2013, algorithm 9.3).
//!
//! For events `k = 0 .. n-1` with filtered beliefs `(x_k, P_k)`, and the
//! prediction to event `k+1` (prior `(x-_{k+1}, P-_{k+1})`, Jacobian
//! `F_{k+1}`), going backwards from `(xs_{n-1}, Ps_{n-1}) = (x_{n-1},
//! P_{n-1})`:
//!
//! `C_k = P_k F_{k+1}^T (P-_{k+1})^-1`,
//! `xs_k = x_k + C_k (xs_{k+1} - x-_{k+1})`,
//! `Ps_k = P_k + C_k (Ps_{k+1} - P-_{k+1}) C_k^T`.
//!
//! Angles (heading, bearing bias) are differenced on the circle and the
//! result wrapped.

use locus_core::nalgebra::Cholesky;
use locus_core::{Belief, MotionModel, wrap_angle};
use locus_models::calibrated_unicycle::{BEARING_BIAS, CalibratedUnicycle, Propagation};
use locus_models::unicycle::Velocities;

use crate::{STATE, StateMatrix, StateVector};

/// What the backward pass needs of one event of the forward pass: the
/// prediction from one event to the next is recomputed from these, with the
/// same model and the same operations as the forward pass, so it is the
/// forward pass's to the bit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Node {
    /// The belief after the event.
    pub posterior: Belief<f64, STATE>,
    /// The event's time, s.
    pub time: f64,
    /// The forward speed in force after the event (as logged), m/s.
    pub v: f64,
    /// The turn rate in force after the event (as logged), rad/s.
    pub omega: f64,
}

/// The prior at `next` predicted from `here`, with the prediction's
/// Jacobian `F` and `F P` (`None` if the prediction fails): the forward
/// pass's [`locus_core::Ekf::predict`] (the same checks, and the model's
/// `propagate`, of which this is the by-product-keeping form), so the prior
/// is the forward pass's to the bit.
fn prediction(
    model: &CalibratedUnicycle<f64>,
    here: &Node,
    next: &Node,
) -> Option<Propagation<f64>> {
    let dt = next.time - here.time;
    let b = &here.posterior;
    if dt > 0.0 {
        let u = Velocities {
            v: here.v,
            omega: here.omega,
            dt,
        };
        let finite = |m: &[f64]| m.iter().all(|v| v.is_finite());
        if !(model.input_is_finite(&u) && finite(b.x.as_slice()) && finite(b.p.as_slice())) {
            return None;
        }
        let step = model.propagate_linearized(&b.x, &u, &b.p);
        (finite(step.x.as_slice()) && finite(step.p.as_slice())).then_some(step)
    } else {
        Some(Propagation {
            x: b.x,
            p: b.p,
            a: StateMatrix::identity(),
            ap: b.p,
        })
    }
}

fn wrap_angles(mut v: StateVector) -> StateVector {
    v[2] = wrap_angle(v[2]);
    v[BEARING_BIAS] = wrap_angle(v[BEARING_BIAS]);
    v
}

/// Runs the backward pass over `nodes`, handing each smoothed belief to
/// `keep` with its index, from the last node to the first (the caller keeps
/// what it needs: the pass holds only the belief ahead).
///
/// # Errors
/// The index of the event whose prediction fails or whose predicted
/// covariance is not positive definite.
pub(crate) fn rts(
    model: &CalibratedUnicycle<f64>,
    nodes: &[Node],
    mut keep: impl FnMut(usize, &Belief<f64, STATE>),
) -> Result<(), usize> {
    let Some(last) = nodes.last() else {
        return Ok(());
    };
    let mut ahead = last.posterior;
    keep(nodes.len() - 1, &ahead);
    for k in (0..nodes.len() - 1).rev() {
        if nodes[k + 1].time == nodes[k].time {
            // No prediction between them: C = I, the smoothed belief is
            // the next one's.
            keep(k, &ahead);
            continue;
        }
        let prior = prediction(model, &nodes[k], &nodes[k + 1]).ok_or(k + 1)?;
        let here = &nodes[k].posterior;
        // C^T = (P-)^-1 F P, as the solution of P- C^T = F P.
        let ct = Cholesky::new(prior.p).ok_or(k + 1)?.solve(&prior.ap);
        let dx = wrap_angles(ahead.x - prior.x);
        let x = wrap_angles(here.x + ct.tr_mul(&dx));
        // Ps = P + C (Ps+ - P-) C^T: one triangle, the other mirrored.
        let m = ct.tr_mul(&(ahead.p - prior.p));
        let mut p = here.p;
        for c in 0..STATE {
            for r in c..STATE {
                let mut v = 0.0;
                for i in 0..STATE {
                    v += m[(r, i)] * ct[(i, c)];
                }
                p[(r, c)] += v;
                p[(c, r)] = p[(r, c)];
            }
        }
        ahead = Belief::new(x, p);
        keep(k, &ahead);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use locus_core::Ekf;

    /// The robot standing still, heading 0: its x is a random walk of
    /// variance `psd_v` per second, independent of the other states. Seen
    /// directly each second, the smoother's x at each step must equal the
    /// batch least-squares estimate over all measurements (computed
    /// independently, in information form).
    #[test]
    fn matches_the_batch_solution_of_a_random_walk() {
        let (q, r, p0) = (0.3, 0.5, 2.0);
        let model = CalibratedUnicycle {
            psd_v: q,
            psd_omega: 0.1,
            walk: [1e-3; 4],
        };
        let z = [1.0, 1.4, 0.7, 2.0, 1.1, 0.4];
        let n = z.len();
        let mut nodes: Vec<Node> = Vec::new();
        let mut belief = Belief::new(StateVector::zeros(), StateMatrix::identity());
        belief.x[3] = 1.0;
        belief.x[4] = 1.0;
        belief.p[(0, 0)] = p0;
        for (k, zk) in z.iter().enumerate() {
            if let Some(prev) = nodes.last() {
                let u = Velocities {
                    v: 0.0,
                    omega: 0.0,
                    dt: 1.0,
                };
                assert_eq!(prev.time + 1.0, k as f64);
                belief = Ekf::default().predict(&prev.posterior, &model, &u).unwrap();
            }
            let (xp, pp) = (belief.x[0], belief.p[(0, 0)]);
            let g = pp / (pp + r);
            belief.x[0] = xp + g * (zk - xp);
            belief.p[(0, 0)] = (1.0 - g) * pp;
            nodes.push(Node {
                posterior: belief,
                time: k as f64,
                v: 0.0,
                omega: 0.0,
            });
        }
        let mut s = vec![nodes[0].posterior; n];
        rts(&model, &nodes, |k, b| s[k] = *b).unwrap();
        // Batch: minimise x0^2/p0 + sum (z_k - x_k)^2/r + sum (x_k - x_{k-1})^2/q.
        let mut a = locus_core::nalgebra::SMatrix::<f64, 6, 6>::zeros();
        let mut b = locus_core::nalgebra::SVector::<f64, 6>::zeros();
        a[(0, 0)] += 1.0 / p0;
        for k in 0..n {
            a[(k, k)] += 1.0 / r;
            b[k] += z[k] / r;
            if k > 0 {
                a[(k, k)] += 1.0 / q;
                a[(k - 1, k - 1)] += 1.0 / q;
                a[(k, k - 1)] -= 1.0 / q;
                a[(k - 1, k)] -= 1.0 / q;
            }
        }
        let cov = a.try_inverse().unwrap();
        let xb = cov * b;
        for k in 0..n {
            assert!((s[k].x[0] - xb[k]).abs() < 1e-12, "mean at {k}");
            assert!(
                (s[k].p[(0, 0)] - cov[(k, k)]).abs() < 1e-12,
                "variance at {k}"
            );
        }
        // The last step has no future: smoothed = filtered.
        assert_eq!(s[n - 1], nodes[n - 1].posterior);
    }
}
