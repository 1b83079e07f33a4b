//! Relative pose errors (Kuemmerle et al., "On measuring the accuracy of
//! SLAM algorithms", Autonomous Robots 27(4), 2009): a trajectory judged by
//! the relative motions between pairs of times, measured independently
//! (the Intel lab's relations were verified by hand), rather than against a
//! global truth that may itself come from the estimator being judged.
//!
//! For a relation `delta` (the pose at `t2` in the frame of the pose at
//! `t1`) and the estimated poses `x1`, `x2` at those times, the error is
//! `e = (x1^-1 (+) x2) (-) delta`, composed in SE(2); its translational
//! part is `|(e_x, e_y)|` (m) and its rotational part `|wrap(e_theta)|`
//! (rad). Units: m, rad.

use locus_core::wrap_angle;

pub use locus_logs::relations::Relation;

/// `b` in the frame of `a` (`a^-1 (+) b`), poses `[x, y, theta]`.
#[must_use]
pub fn between(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let (s, c) = a[2].sin_cos();
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    [c * dx + s * dy, -s * dx + c * dy, wrap_angle(b[2] - a[2])]
}

/// The translational (m) and rotational (rad) error of the estimated
/// relative pose `estimated` (from [`between`]) against `r`.
#[must_use]
pub fn error(estimated: [f64; 3], r: &Relation) -> (f64, f64) {
    let e = between([r.dx, r.dy, r.dyaw], estimated);
    (e[0].hypot(e[1]), e[2].abs())
}

/// The errors of a trajectory over a set of relations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelationErrors {
    /// Relations whose two times the trajectory covers.
    pub judged: usize,
    /// Relations left out: a time the trajectory does not cover.
    pub uncovered: usize,
    /// Mean translational error, m; NaN when none was judged.
    pub mean_translation: f64,
    /// Its standard deviation over the relations (divided by their
    /// count), m; NaN when none was judged.
    pub std_translation: f64,
    /// Mean rotational error, rad; NaN when none was judged.
    pub mean_rotation: f64,
    /// Its standard deviation over the relations (divided by their
    /// count), rad; NaN when none was judged.
    pub std_rotation: f64,
}

/// The errors of the trajectory `pose_at` (the pose at a time, `None` where
/// it has none) over `relations`.
#[must_use]
pub fn evaluate(
    relations: &[Relation],
    mut pose_at: impl FnMut(f64) -> Option<[f64; 3]>,
) -> RelationErrors {
    judge(relations.iter().map(|r| (r, pose_at(r.t1), pose_at(r.t2))))
}

/// The errors of a trajectory known at indices (e.g. a log's scans; `pose`
/// gives the pose at an index, `None` where it has none) over `relations`,
/// whose ends fall on the indices `ends` (one per relation, `None` when
/// they fall on none: `locus_logs::relations::on_scans`). A relation whose
/// ends fall on no index, or on one without a pose, is uncovered.
///
/// # Panics
/// If `ends` is not as long as `relations`.
#[must_use]
pub fn evaluate_at(
    relations: &[Relation],
    ends: &[Option<(usize, usize)>],
    mut pose: impl FnMut(usize) -> Option<[f64; 3]>,
) -> RelationErrors {
    assert_eq!(relations.len(), ends.len(), "one pair of ends per relation");
    judge(relations.iter().zip(ends).map(|(r, e)| match *e {
        Some((i, j)) => (r, pose(i), pose(j)),
        None => (r, None, None),
    }))
}

/// The errors of each relation with the trajectory's poses at its two ends.
#[allow(clippy::cast_precision_loss)]
fn judge<'a>(
    pairs: impl Iterator<Item = (&'a Relation, Option<[f64; 3]>, Option<[f64; 3]>)>,
) -> RelationErrors {
    let mut t = Vec::new();
    let mut r = Vec::new();
    let mut uncovered = 0;
    for (rel, a, b) in pairs {
        match (a, b) {
            (Some(a), Some(b)) => {
                let (et, er) = error(between(a, b), rel);
                t.push(et);
                r.push(er);
            }
            _ => uncovered += 1,
        }
    }
    let stats = |v: &[f64]| {
        if v.is_empty() {
            return (f64::NAN, f64::NAN);
        }
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        (mean, var.sqrt())
    };
    let (mean_translation, std_translation) = stats(&t);
    let (mean_rotation, std_rotation) = stats(&r);
    RelationErrors {
        judged: t.len(),
        uncovered,
        mean_translation,
        std_translation,
        mean_rotation,
        std_rotation,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trajectory_that_agrees_with_its_relations_has_no_error() {
        let poses = [[1.0, 2.0, 0.3], [2.0, 2.5, 1.0], [0.5, 3.0, -2.8]];
        let relations: Vec<Relation> = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| {
                let d = between(poses[i], poses[j]);
                Relation {
                    t1: i as f64,
                    t2: j as f64,
                    dx: d[0],
                    dy: d[1],
                    dyaw: d[2],
                    line: 0,
                }
            })
            .collect();
        let e = evaluate(&relations, |t| poses.get(t as usize).copied());
        assert_eq!(e.judged, 9);
        assert!(
            e.mean_translation < 1e-12 && e.mean_rotation < 1e-12,
            "{e:?}"
        );
    }

    #[test]
    fn a_relation_off_by_a_known_motion_has_that_error() {
        // The relation says 1 m ahead; the trajectory moved 1 m ahead and
        // 0.1 m left, turned 0.05 rad: error 0.1 m, 0.05 rad.
        let r = Relation {
            t1: 0.0,
            t2: 1.0,
            dx: 1.0,
            dy: 0.0,
            dyaw: 0.0,
            line: 0,
        };
        let a = [3.0, -1.0, 0.7];
        let (s, c) = 0.7_f64.sin_cos();
        let b = [3.0 + c - s * 0.1, -1.0 + s + c * 0.1, 0.75];
        let (et, er) = error(between(a, b), &r);
        assert!(
            (et - 0.1).abs() < 1e-12 && (er - 0.05).abs() < 1e-12,
            "{et} {er}"
        );
    }

    #[test]
    fn uncovered_relations_are_counted_and_none_judged_is_nan() {
        let r = Relation {
            t1: 0.0,
            t2: 1.0,
            dx: 1.0,
            dy: 0.0,
            dyaw: 0.0,
            line: 0,
        };
        let e = evaluate(&[r], |_| None);
        assert_eq!((e.judged, e.uncovered), (0, 1));
        assert!(e.mean_translation.is_nan() && e.mean_rotation.is_nan());
    }

    #[test]
    fn relations_judged_at_indices_count_those_on_no_index_as_uncovered() {
        // Poses at three scans; the relations' ends on scans (0, 1), on
        // none, and on (1, 2) where scan 2 has no pose.
        let poses = [Some([0.0, 0.0, 0.0]), Some([1.0, 0.2, 0.1]), None];
        let r = |dx: f64| Relation {
            t1: 0.0,
            t2: 1.0,
            dx,
            dy: 0.2,
            dyaw: 0.1,
            line: 0,
        };
        let rel = [r(1.0), r(1.0), r(0.9)];
        let ends = [Some((0, 1)), None, Some((1, 2))];
        let e = evaluate_at(&rel, &ends, |i| poses[i]);
        assert_eq!((e.judged, e.uncovered), (1, 2));
        assert!(
            e.mean_translation < 1e-12 && e.std_translation == 0.0,
            "{e:?}"
        );
        // Two judged: errors 0 and 0.1 m, mean 0.05, standard deviation 0.05.
        let all = [Some([0.0, 0.0, 0.0]), Some([1.0, 0.2, 0.1])];
        let e = evaluate_at(&[r(1.0), r(0.9)], &[Some((0, 1)); 2], |i| all[i]);
        assert!(
            (e.mean_translation - 0.05).abs() < 1e-12 && (e.std_translation - 0.05).abs() < 1e-12,
            "{e:?}"
        );
    }
}
