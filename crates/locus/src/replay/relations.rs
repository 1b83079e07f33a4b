//! `locus replay carmen FILE --relations RELATIONS`: the replay judged
//! against relative poses measured apart from the log (the Intel lab's
//! hand-verified relations, Kuemmerle et al., "On measuring the accuracy of
//! SLAM algorithms", Autonomous Robots 27(4), 2009), beside the log's own
//! corrected poses and its raw odometry judged alike.
//!
//! A relation's two times fall on two scans when each is within
//! [`MATCH_TOLERANCE`] of a scan's stamp as recorded (the Intel log's
//! stamps have two decimals: docs/log-format.md). A scan that two
//! different relation times fall on is ambiguous: the relations come from
//! a log with more scans, and the stamp's rounding cannot tell which of
//! the two times is this scan's (on the Intel lab, 10 scans; among them
//! pairs of times 5.6 ms apart with 0.35 m of motion between them). The
//! relations with an end on an ambiguous scan are left out
//! ([`unambiguous`]: 14 of the Intel lab's 119 on scans).
//!
//! At a scan the trajectories are: the filter's estimate after the scan's
//! correction; the smoother's at the same event; the corrected pose of the
//! scan; and raw odometry, the log's `ODOM` poses composed from scan to
//! scan from the first corrected pose
//! (`locus_logs::carmen::Carmen::raw_motion`: no filter, no calibration, no
//! delay, nothing refused). Relative errors do not depend on where a
//! trajectory starts.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use anyhow::{Context, Result};
use comfy_table::Table;
use locus_core::Belief;
use locus_core::nalgebra::Matrix3;
use locus_eval::reference_error::{ReferenceError, consistency, reference_error};
use locus_eval::relations::{Relation, evaluate_at};
use locus_eval::results::{Consistency, ConsistencyAtScans, RelationFigures, Relations};
use locus_logs::carmen::Carmen;
use locus_logs::se2::compose;
use locus_replay::{EventKind, Step};

use crate::table::{fig, with_header};

/// How near a scan's recorded stamp a relation's time must be to fall on
/// it, s: the Intel log's stamps are rounded to 10 ms above 1000 s, so
/// 5 ms is their rounding (119 of its relations fall on scans).
pub const MATCH_TOLERANCE: f64 = 5e-3;

/// The relations of a log and the trajectories that need no replay: the
/// log's truth and its raw odometry at each scan.
#[derive(Debug)]
pub struct Reference {
    /// The file's name, for the table.
    name: String,
    /// Every relation of the file.
    relations: Vec<Relation>,
    /// For each relation, the scans its ends fall on (`None` if not both,
    /// or one is ambiguous).
    ends: Vec<Option<(usize, usize)>>,
    /// Relations with both ends on scans.
    on_scans: usize,
    /// Of those, the ones left out with an end on an ambiguous scan.
    ambiguous: usize,
    /// The corrected pose of each scan.
    truth: Vec<[f64; 3]>,
    /// Raw odometry at each scan.
    odometry: Vec<[f64; 3]>,
}

impl Reference {
    /// The relations of the file at `path`, shifted by `-offset` (s) into
    /// the time base of the CARMEN log `carmen`, on its scans.
    ///
    /// # Errors
    /// A relations file that cannot be read, naming the file (and line).
    pub fn carmen(carmen: &Carmen, path: &Path, offset: f64) -> Result<Self> {
        let relations = locus_logs::relations::read(path, offset)
            .with_context(|| format!("reading the relations {}", path.display()))?;
        let mut ends =
            locus_logs::relations::on_scans(&relations, &carmen.scan_stamps, MATCH_TOLERANCE);
        let on_scans = ends.iter().flatten().count();
        let ambiguous = unambiguous(&relations, &mut ends);
        let truth: Vec<[f64; 3]> = carmen
            .scan_poses
            .iter()
            .map(|p| [p.x, p.y, p.theta])
            .collect();
        let mut odometry = Vec::with_capacity(truth.len());
        if let Some(&first) = truth.first() {
            odometry.push(first);
            for m in &carmen.raw_motion {
                let last = odometry[odometry.len() - 1];
                odometry.push(compose(last, *m));
            }
        }
        Ok(Self {
            name: path
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
            relations,
            ends,
            on_scans,
            ambiguous,
            truth,
            odometry,
        })
    }

    /// Where the replay's estimates at the scans are gathered.
    #[must_use]
    pub fn gather(&self) -> AtScans {
        AtScans {
            filter: vec![None; self.truth.len()],
            smoother: vec![None; self.truth.len()],
        }
    }

    /// The truth's own error at a scan, from its errors over the relations
    /// on scans (`None` with too few).
    fn truth_error(&self) -> Option<ReferenceError> {
        reference_error(&self.relations, &self.ends, |i| self.truth.get(i).copied())
    }

    /// The consistency of the estimates `at` (one per scan) with the truth
    /// at the scans, alone and with the truth's error `error`.
    fn consistency(&self, at: &[Option<Estimate>], error: Option<&ReferenceError>) -> Consistency {
        let pairs = at
            .iter()
            .zip(&self.truth)
            .filter_map(|(e, &t)| e.map(|(x, p)| (x, p, t)));
        Consistency::from(&consistency(pairs, error))
    }

    /// The errors over the relations on scans of the trajectory `pose`.
    fn figures(&self, pose: impl FnMut(usize) -> Option<[f64; 3]>) -> RelationFigures {
        RelationFigures::from(&evaluate_at(&self.relations, &self.ends, pose))
    }

    /// The `relations` section: the filter's (and, with `smoothed`, the
    /// smoother's) estimates at the scans, the truth and raw odometry,
    /// judged over the relations on scans; the truth's own error from them,
    /// and the estimates' consistency with the truth alone and with it.
    #[must_use]
    pub fn judge(&self, at: &AtScans, smoothed: bool) -> Relations {
        let error = self.truth_error();
        Relations {
            in_file: self.relations.len(),
            on_scans: self.on_scans,
            ambiguous: self.ambiguous,
            match_tolerance_s: MATCH_TOLERANCE,
            filter: self.figures(|i| pose(&at.filter, i)),
            smoother: smoothed.then(|| self.figures(|i| pose(&at.smoother, i))),
            truth: self.figures(|i| self.truth.get(i).copied()),
            odometry: self.figures(|i| self.odometry.get(i).copied()),
            truth_error: error.as_ref().map(Into::into),
            consistency: ConsistencyAtScans {
                filter: self.consistency(&at.filter, error.as_ref()),
                smoother: smoothed.then(|| self.consistency(&at.smoother, error.as_ref())),
            },
        }
    }

    /// The table of `r` ([`Reference::judge`]), with a line above it
    /// saying how many relations fell on scans.
    #[must_use]
    pub fn table(&self, r: &Relations) -> String {
        let deg = 180.0 / core::f64::consts::PI;
        let mut t: Table = with_header([
            "against the relations",
            "relations compared [count]",
            "mean translational error [m]",
            "its std dev [m]",
            "mean rotational error [deg]",
            "its std dev [deg]",
        ]);
        let rows = [
            Some(("filter", r.filter)),
            r.smoother.map(|s| ("smoother", s)),
            Some(("corrected poses (the log's truth)", r.truth)),
            Some(("raw odometry (the log's ODOM poses)", r.odometry)),
        ];
        for (name, f) in rows.into_iter().flatten() {
            t.add_row(vec![
                name.to_string(),
                f.compared.to_string(),
                fig(f.mean_translation_m, 1.0, 3),
                fig(f.std_translation_m, 1.0, 3),
                fig(f.mean_rotation_rad, deg, 2),
                fig(f.std_rotation_rad, deg, 2),
            ]);
        }
        format!(
            "relations ({}): {} in the file; {} with both ends within {} ms of a scan's stamp, \
             {} of them left out as ambiguous (an end on a scan that two different relation \
             times fall on)\n{t}\n{}",
            self.name,
            r.in_file,
            r.on_scans,
            MATCH_TOLERANCE * 1e3,
            r.ambiguous,
            consistency_table(r),
        )
    }
}

/// The table of the estimates' consistency with the truth at the scans,
/// alone and with the truth's own error, after a line giving that error.
fn consistency_table(r: &Relations) -> String {
    let deg = 180.0 / core::f64::consts::PI;
    let error = r.truth_error.map_or_else(
        || {
            format!(
                "the truth's own error: n/a (fewer than {} relations judged)",
                locus_eval::reference_error::MIN_RELATIONS
            )
        },
        |e| {
            format!(
                "the truth's own error at a pose, from its errors over the {} relations \
                 (robust; all of their disagreement counted as the truth's, so at most): \
                 {} m in x and in y, {} deg in heading",
                e.relations,
                fig(e.sigma_xy_m, 1.0, 4),
                fig(e.sigma_heading_rad, deg, 2),
            )
        },
    );
    let mut t: Table = with_header([
        "at the scans, against the truth",
        "scans compared [count]",
        "inside 3 sigma x / y / heading [%]",
        "mean NEES [-] (3 if honest)",
        "with the truth's error: inside 3 sigma x / y / heading [%]",
        "with the truth's error: mean NEES [-]",
    ]);
    let shares = |s: [f64; 3]| s.map(|v| fig(v, 100.0, 1)).join(" / ");
    let rows = [
        Some(("filter", r.consistency.filter)),
        r.consistency.smoother.map(|s| ("smoother", s)),
    ];
    for (name, c) in rows.into_iter().flatten() {
        t.add_row(vec![
            name.to_string(),
            c.compared.to_string(),
            shares([
                c.within_3_sigma_x_share,
                c.within_3_sigma_y_share,
                c.within_3_sigma_heading_share,
            ]),
            fig(c.mean_nees, 1.0, 2),
            shares([
                c.with_truth_error_within_3_sigma_x_share,
                c.with_truth_error_within_3_sigma_y_share,
                c.with_truth_error_within_3_sigma_heading_share,
            ]),
            fig(c.with_truth_error_mean_nees, 1.0, 2),
        ]);
    }
    format!("{error}\n{t}\n")
}

/// Leaves out (sets to `None`) the `ends` of the relations with an end on
/// a scan that two different relation times fall on; returns how many it
/// left out. `ends` are those of `relations` (`on_scans`).
fn unambiguous(relations: &[Relation], ends: &mut [Option<(usize, usize)>]) -> usize {
    // The first relation time to fall on each scan, and whether another did.
    let mut first: HashMap<usize, f64> = HashMap::new();
    let mut ambiguous: HashSet<usize> = HashSet::new();
    for (r, e) in relations.iter().zip(ends.iter()) {
        let Some((i, j)) = *e else { continue };
        for (scan, t) in [(i, r.t1), (j, r.t2)] {
            let t0 = *first.entry(scan).or_insert(t);
            // The same time in two relations is one scan of theirs.
            if (t - t0).abs() > 1e-6 {
                ambiguous.insert(scan);
            }
        }
    }
    let mut left_out = 0;
    for e in ends.iter_mut() {
        if let Some((i, j)) = *e
            && (ambiguous.contains(&i) || ambiguous.contains(&j))
        {
            *e = None;
            left_out += 1;
        }
    }
    left_out
}

/// An estimate at a scan: the pose and its covariance.
type Estimate = ([f64; 3], Matrix3<f64>);

/// The pose of the estimate at scan `i`, if any.
fn pose(at: &[Option<Estimate>], i: usize) -> Option<[f64; 3]> {
    at.get(i).copied().flatten().map(|(x, _)| x)
}

/// The replay's estimates at each scan, gathered from its steps.
#[derive(Debug)]
pub struct AtScans {
    filter: Vec<Option<Estimate>>,
    smoother: Vec<Option<Estimate>>,
}

impl AtScans {
    /// Keeps the estimates of `step` if it is a scan.
    pub fn take(&mut self, step: &Step) {
        let of = |b: &Belief<f64, 3>| -> Estimate { ([b.x[0], b.x[1], b.x[2]], b.p) };
        if let EventKind::Scan { index, .. } = step.kind
            && let Some(slot) = self.filter.get_mut(index)
        {
            *slot = Some(of(&step.belief));
            self.smoother[index] = step.smoothed.as_ref().map(of);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(t1: f64, t2: f64) -> Relation {
        Relation {
            t1,
            t2,
            dx: 1.0,
            dy: 0.0,
            dyaw: 0.0,
            line: 0,
        }
    }

    #[test]
    fn relations_with_an_end_on_a_scan_two_times_fall_on_are_left_out() {
        // Scan 2 is where 20.001 and 20.004 both fall; scan 1 is 10.0 in
        // two relations (one time: not ambiguous).
        let r = [
            rel(0.0, 10.0),
            rel(10.0, 20.001),
            rel(20.004, 30.0),
            rel(10.0, 30.0),
            rel(20.001, 20.004),
        ];
        let mut ends = vec![
            Some((0, 1)),
            Some((1, 2)),
            Some((2, 3)),
            Some((1, 3)),
            Some((2, 2)),
        ];
        assert_eq!(unambiguous(&r, &mut ends), 3);
        assert_eq!(ends, [Some((0, 1)), None, None, Some((1, 3)), None]);
    }
}
