//! Ground-truth lookups at times that mostly do not decrease, without a
//! binary search of the whole track per lookup.
//!
//! A replay asks for the ground truth at every event's time, and those
//! times rise by a sample or two at a time; [`TruthCursor`] keeps the
//! position of its previous lookup and walks forward from it. When the
//! time goes back, or jumps further than a short walk, it falls back to a
//! binary search of the part of the track that can hold the answer, so any
//! sequence of times gets the same answers as [`Groundtruth::pose_at`].
//!
//! [`Groundtruth::pose_at`]: crate::mrclam::Groundtruth::pose_at

use crate::mrclam::{Groundtruth, TruthPose, interpolate};

/// Samples walked forward one by one before a lookup switches to a binary
/// search of the rest of the track.
const WALK: usize = 8;

/// A position in a [`Groundtruth`] track, for successive lookups; made by
/// [`Groundtruth::cursor`].
///
/// [`Groundtruth`]: crate::mrclam::Groundtruth
/// [`Groundtruth::cursor`]: crate::mrclam::Groundtruth::cursor
#[derive(Debug, Clone)]
pub struct TruthCursor<'a> {
    /// The track.
    track: &'a Groundtruth,
    /// The track's poses, in non-decreasing time order.
    poses: &'a [TruthPose],
    /// The index of the first pose later than the previous lookup's time
    /// (0 before the first lookup): every pose before it is no later than
    /// that time.
    after: usize,
}

impl<'a> TruthCursor<'a> {
    /// A cursor at the start of `track`.
    pub(crate) fn new(track: &'a Groundtruth) -> Self {
        Self {
            track,
            poses: track.poses(),
            after: 0,
        }
    }

    /// The pose at time `t` (s): exactly what [`Groundtruth::pose_at`]
    /// returns for `t` and `max_gap` (s) (linear interpolation, theta the
    /// short way round, NaN for a track with no heading; `None` outside the
    /// track or across a gap wider than `max_gap`), at the cost of a few comparisons when `t` is at or a
    /// little after the previous lookup's time.
    ///
    /// [`Groundtruth::pose_at`]: crate::mrclam::Groundtruth::pose_at
    pub fn pose_at(&mut self, t: f64, max_gap: f64) -> Option<TruthPose> {
        self.after = self.seek(t);
        interpolate(self.poses, self.after, t, max_gap).map(|p| self.track.headed(p))
    }

    /// The index of the first pose whose time is `> t` (`poses.len()` if
    /// none): the partition point `Groundtruth::pose_at` searches for.
    fn seek(&self, t: f64) -> usize {
        let poses = self.poses;
        let mut i = self.after;
        // Times are sorted, so `time <= t` holds for a prefix of the track.
        // If the pose before the cursor is later than `t` (or `t` is NaN),
        // that prefix ends before the cursor.
        if i > 0
            && matches!(
                poses[i - 1].time.partial_cmp(&t),
                Some(core::cmp::Ordering::Greater) | None
            )
        {
            return poses[..i].partition_point(|p| p.time <= t);
        }
        // Otherwise it ends at or after the cursor.
        for _ in 0..WALK {
            match poses.get(i) {
                Some(p) if p.time <= t => i += 1,
                _ => return i,
            }
        }
        i + poses[i..].partition_point(|p| p.time <= t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mrclam::Groundtruth;
    use core::f64::consts::PI;
    use proptest::prelude::*;

    /// Whether the cursor stands where a search of the whole track for `t`
    /// ends.
    fn at_search(g: &Groundtruth, c: &TruthCursor<'_>, t: f64) -> bool {
        c.after == g.poses().partition_point(|p| p.time <= t)
    }

    fn pose(time: f64, x: f64, theta: f64) -> TruthPose {
        TruthPose {
            time,
            x,
            y: -x,
            theta,
        }
    }

    /// The pose's fields as bits, so that equal means identical.
    fn bits(p: Option<TruthPose>) -> Option<[u64; 4]> {
        p.map(|p| [p.time, p.x, p.y, p.theta].map(f64::to_bits))
    }

    #[test]
    fn walks_forward_back_and_far() {
        let g = Groundtruth::new(
            (0..100)
                .map(|i| {
                    pose(
                        f64::from(i / 2) * 0.01,
                        f64::from(i),
                        0.03 * f64::from(i) - 1.5,
                    )
                })
                .collect(),
        )
        .unwrap();
        let mut c = g.cursor();
        for t in [
            -1.0,
            0.0,
            0.0,
            0.003,
            0.01,
            0.011,
            0.3,
            0.2,
            0.49,
            0.495,
            0.5,
            f64::NAN,
            0.1,
        ] {
            assert_eq!(
                bits(c.pose_at(t, 0.05)),
                bits(g.pose_at(t, 0.05)),
                "t = {t}"
            );
            assert!(at_search(&g, &c, t), "t = {t}");
        }
        assert!(Groundtruth::default().cursor().pose_at(0.0, 1.0).is_none());
    }

    /// A track of up to 40 poses with repeated times (times on a coarse
    /// grid), headings anywhere in (-pi, pi].
    fn track() -> impl Strategy<Value = Groundtruth> {
        proptest::collection::vec((0u32..60, -10.0..10.0f64, -PI..PI), 0..40).prop_map(|mut v| {
            v.sort_by_key(|(k, _, _)| *k);
            let poses = v
                .into_iter()
                .map(|(k, x, theta)| pose(f64::from(k) * 0.05, x, theta))
                .collect();
            Groundtruth::new(poses).unwrap()
        })
    }

    /// Query times: mostly small steps forward, with repeats, steps back,
    /// long jumps, sample times exactly and times off the track.
    fn queries() -> impl Strategy<Value = Vec<f64>> {
        let step = prop_oneof![
            6 => 0.0..0.04f64,
            2 => Just(0.0),
            1 => -0.5..0.0f64,
            1 => 0.0..3.5f64,
            1 => (0u32..60).prop_map(|k| f64::from(k) * 0.05 + 1e6),
        ];
        (-0.2..0.5f64, proptest::collection::vec(step, 0..80)).prop_map(|(t0, steps)| {
            let mut t = t0;
            steps
                .into_iter()
                .map(|s| {
                    // Codes above 1e5 are absolute sample times, not steps.
                    t = if s > 1e5 { s - 1e6 } else { t + s };
                    t
                })
                .collect()
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        #[test]
        fn the_cursor_answers_as_the_search(g in track(), ts in queries(), gap in 0.01..0.3f64) {
            let mut c = g.cursor();
            for &t in &ts {
                prop_assert_eq!(bits(c.pose_at(t, gap)), bits(g.pose_at(t, gap)), "t = {}", t);
                prop_assert!(at_search(&g, &c, t));
            }
        }
    }
}
