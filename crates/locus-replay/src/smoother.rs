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

use locus_eval::Tally;

use crate::engine::{Checkpoint, Engine, judged};
use crate::filter::{calibration_of, pose_belief};
use crate::instants::InstantTally;
use crate::{Error, STATE, StateMatrix, StateVector, Step};

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
/// `next` is the node that follows the last of `nodes` with its smoothed
/// belief, when `nodes` is one segment of a longer pass whose later part
/// is already smoothed; `None` when the last of `nodes` is the pass's last
/// (its smoothed belief is its filtered one). Either way each belief comes
/// from the same operations on the same values, so smoothing a pass in
/// segments, last first, gives the whole pass's beliefs to the bit.
///
/// # Errors
/// The time of the event whose prediction fails or whose predicted
/// covariance is not positive definite, s.
pub(crate) fn rts(
    model: &CalibratedUnicycle<f64>,
    nodes: &[Node],
    next: Option<(&Node, &Belief<f64, STATE>)>,
    mut keep: impl FnMut(usize, &Belief<f64, STATE>),
) -> Result<(), f64> {
    let Some(last) = nodes.last() else {
        return Ok(());
    };
    let (mut ahead, end, beyond) = match next {
        Some((node, smoothed)) => (*smoothed, nodes.len(), Some(node)),
        None => {
            keep(nodes.len() - 1, &last.posterior);
            (last.posterior, nodes.len() - 1, None)
        }
    };
    for k in (0..end).rev() {
        // Past the last node only with a `next` (`end` stops before it
        // otherwise).
        let Some(following) = nodes.get(k + 1).or(beyond) else {
            break;
        };
        if following.time == nodes[k].time {
            // No prediction between them: C = I, the smoothed belief is
            // the next one's.
            keep(k, &ahead);
            continue;
        }
        let prior = prediction(model, &nodes[k], following).ok_or(following.time)?;
        let here = &nodes[k].posterior;
        // C^T = (P-)^-1 F P, as the solution of P- C^T = F P.
        let ct = Cholesky::new(prior.p)
            .ok_or(following.time)?
            .solve(&prior.ap);
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

/// The end of a smoothed replay: the backward pass over the forward pass
/// `engine` has made, then each step to `sink` in order with its smoothed
/// estimate; the report gets the smoother's figures.
///
/// `checkpoints[j]` is the forward pass's state at the start of segment
/// `j` (the first at step 0). With one, `engine` holds every step already.
/// With more, the segments are re-made from their checkpoints: from the
/// last to the second for the backward pass, which keeps of each only its
/// first node and that node's smoothed belief; then from the first to the
/// last, each smoothed again from the next one's first belief (the same
/// operations on the same values: the same beliefs to the bit) and handed
/// over. Memory: one segment and the checkpoints; time: the forward pass
/// twice more and the backward pass once more.
///
/// # Errors
/// [`Error::Smoother`]; the forward pass's errors (which its first run
/// would have met).
pub(crate) fn flush<'a>(
    engine: &mut Engine<'a>,
    mut checkpoints: Vec<Checkpoint<'a>>,
    sink: &mut impl FnMut(&Step),
) -> Result<(), Error> {
    let remade = checkpoints.len() > 1;
    // A checkpoint taken after the last step starts no segment.
    if remade
        && checkpoints
            .last()
            .is_some_and(|c| c.next_index == engine.next_index)
    {
        checkpoints.pop();
    }
    let report = engine.report.clone();
    let model = engine.cfg.motion_model();
    let fresh = Tally::new(3).map_err(|_| Error::InvalidConfig("NEES degrees of freedom"))?;
    let mut held = report.smoothing_held;
    let mut remake = |engine: &mut Engine<'a>, j: usize| -> Result<(), Error> {
        engine.restore(&checkpoints[j])?;
        engine.tally = InstantTally::new(fresh.clone());
        let end = checkpoints.get(j + 1).map(|c| c.next_index);
        while end.is_none_or(|end| engine.next_index < end) && engine.advance()? {}
        // The pass is deterministic: a re-run stops where the next
        // checkpoint was taken, between the same two records.
        debug_assert!(end.is_none_or(|end| engine.next_index == end));
        held = held.max(engine.nodes.len());
        Ok(())
    };
    // bounds[j]: segment j's first node and its smoothed belief.
    let mut bounds: Vec<Option<(Node, Belief<f64, STATE>)>> = vec![None; checkpoints.len() + 1];
    if remade {
        for j in (1..checkpoints.len()).rev() {
            remake(engine, j)?;
            let mut first = None;
            let next = bounds[j + 1].as_ref().map(|(n, b)| (n, b));
            rts(&model, &engine.nodes, next, |k, s| {
                if k == 0 {
                    first = Some(*s);
                }
            })
            .map_err(|time| Error::Smoother { time })?;
            bounds[j] = engine.nodes.first().copied().zip(first);
        }
    }
    let mut tally = InstantTally::new(fresh.clone());
    let mut first_calibration = None;
    for j in 0..checkpoints.len() {
        if remade {
            remake(engine, j)?;
        }
        let steps = &mut engine.held;
        let next = bounds[j + 1].as_ref().map(|(n, b)| (n, b));
        rts(&model, &engine.nodes, next, |k, s| {
            steps[k].smoothed = Some(pose_belief(s));
            steps[k].smoothed_calibration = Some(calibration_of(s).map(|c| c.0));
            if j == 0 && k == 0 {
                first_calibration = Some(calibration_of(s));
            }
        })
        .map_err(|time| Error::Smoother { time })?;
        for step in &engine.held {
            tally.add(step, step.smoothed.as_ref());
            sink(step);
        }
    }
    engine.report = report;
    engine.report.smoothed = Some(judged(tally.summary(), engine.compared_after_start > 0));
    engine.report.smoothed_calibration = first_calibration;
    engine.report.smoothing_held = held;
    engine.report.smoothing_checkpoints = checkpoints.len() - 1;
    engine.held = Vec::new();
    engine.nodes = Vec::new();
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
            range_bias: locus_models::calibrated_unicycle::GaussMarkov {
                sigma: 0.1,
                tau: 2.0,
            },
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
        rts(&model, &nodes, None, |k, b| s[k] = *b).unwrap();
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
