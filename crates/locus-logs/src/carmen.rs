//! A CARMEN log of a 2-D laser and odometry (the Intel Research Lab's
//! "corrected" log: `FLASER` lines with the SLAM-corrected pose, `ODOM`
//! lines of raw odometry restarted from that pose after each scan), read
//! into a Locus log.
//!
//! Lines read (others, e.g. `NEFF`, `SYNC`, are skipped):
//!
//! - `PARAM robot_frontlaser_offset D`: the laser's forward offset from the
//!   robot's origin, m (0 if absent; the Intel log says 0.0);
//! - `FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta ipc_time host
//!   logger_time`: a scan of `n` beams at 1 degree from -90 degrees
//!   ([`ANGLE_0`], [`ANGLE_STEP`]; `n` must be the same on every line) with
//!   the corrected pose `x y theta`;
//! - `ODOM x y theta tv rv accel ipc_time host logger_time`: a pose. The
//!   first `ODOM` after a `FLASER` is the reset to the corrected pose (its
//!   time 0 or garbage; a reset of another pose is an error); the ones after it add raw odometry increments, so the raw
//!   motion from one scan to the next is `(reset)^-1 (+) (last ODOM before
//!   the next scan)`.
//!
//! **Times.** `logger_time` (the Intel log's `ipc_time` equals it on every
//! line). Its stamps are not monotone (an `ODOM` after a scan is often
//! stamped before it; a few scans are stamped before the one before), so
//! the converted times are the stamps made non-decreasing from the end: each
//! event (scan or raw `ODOM`) takes the smallest stamp of itself and every
//! event after it (a stamp that is late is pulled back; [`Carmen::retimed`]
//! counts the stamps changed and [`Carmen::largest_retime`] the largest
//! change). A scan pulled back to within [`MIN_DT`] of the scan before it
//! would squeeze the motion between them into that instant (turns of
//! hundreds of rad/s, which a replay refuses as implausible); it moves to
//! midway between the scans around it when they are at least twice
//! [`MIN_DT`] apart: the raw poses before it are spread in proportion over
//! the longer span, and those after it stamped before its new time take
//! that time ([`Carmen::respaced`] counts the scans moved). [`Carmen::scan_stamps`]
//! keeps the scans' stamps as recorded, to match other files' times
//! against.
//!
//! **Odometry.** Between two scans, the raw poses whose converted time is
//! later than the pose kept before them are kept (a pose stamped no later
//! than the one before is merged into the motion to the next kept pose, or
//! replaces the one before: the composition is unchanged), and of those
//! the ones at least [`MIN_CHORD`] from and [`MIN_DT`] after the pose kept before (the last pose
//! of a segment always ends it, extending the motion before it). Each motion from
//! one kept pose to the next, `(dx, dy, dtheta)` in the frame of the first
//! over `dt`, becomes `odometry` records that dead-reckon it exactly (by the
//! exact integration of the unicycle, `locus_models::unicycle`): one record
//! `v = chord / (dt sinc(dtheta / 2))`, `omega = dtheta / dt` when the chord
//! points at `dtheta / 2` (an arc); otherwise first a turn in place over
//! `dt / 2` by `phi = 2 alpha - dtheta` (`alpha` the chord's direction, or
//! the opposite direction when the robot backs), then the arc over the
//! other `dt / 2`. A record of zero speeds follows the last motion of a
//! segment (the robot waits for the next scan). Odometry starts at the
//! first scan and ends at the last; a segment whose raw poses all carry the
//! time of its scan cannot be given a speed and is counted in
//! [`Carmen::timeless_segments`] (its motion is left out).
//!
//! **Scans and truth.** One `beam_sensor` (id 0, at `robot_frontlaser_offset`
//! forward, [`MIN_RANGE`], [`MAX_RANGE`]), a `scan` per `FLASER` (a reading
//! at or beyond [`MAX_RANGE`], the log's no-return value, becomes `max`),
//! and the corrected pose as `truth,t,x,y,theta` at each scan's time.

use std::path::Path;

use crate::beam_sensor::BeamSensor;
use crate::error::{Error, FieldProblem, RecordProblem, Result};
use crate::locus_csv::LocusLog;
use crate::mrclam::{Groundtruth, Odometry, TruthPose};
use crate::scans::Scans;
use crate::se2::{Pose, relative, sinc, wrap};
use crate::sensor::SensorMount;
use crate::text::{existing, read_text, records};

/// Angle of a scan's first beam from the laser's x axis, rad (-90 degrees).
pub const ANGLE_0: f64 = -core::f64::consts::FRAC_PI_2;

/// Angle between beams, rad (1 degree).
pub const ANGLE_STEP: f64 = core::f64::consts::PI / 180.0;

/// Smallest valid range, m: CARMEN states none, so every reading counts.
pub const MIN_RANGE: f64 = 0.0;

/// The range the Intel log writes for no return (81.83 m): readings at or
/// beyond it become `max`.
pub const MAX_RANGE: f64 = 81.83;

/// A CARMEN log as a Locus log, with what the conversion kept aside.
#[derive(Debug, Clone, PartialEq)]
pub struct Carmen {
    /// The log (see the module documentation).
    pub log: LocusLog,
    /// The corrected pose of each scan, at its converted time.
    pub scan_poses: Vec<TruthPose>,
    /// Each scan's `logger_time` as recorded, s.
    pub scan_stamps: Vec<f64>,
    /// The raw odometry's motion from each scan to the next (`len` one
    /// less than the scans'): `(reset)^-1 (+) (last ODOM before the next
    /// scan)`, in the frame of the first scan's pose.
    pub raw_motion: Vec<Pose>,
    /// Stamps changed to make the times non-decreasing.
    pub retimed: usize,
    /// The largest change of a stamp, s (0 if none).
    pub largest_retime: f64,
    /// Scans moved to midway between their neighbours, having been pulled
    /// back to within [`MIN_DT`] of the scan before.
    pub respaced: usize,
    /// Segments between scans whose motion could not be given a duration
    /// (left out of the odometry).
    pub timeless_segments: usize,
}

/// Reads a CARMEN log at `path` (plain, `.gz` or `.xz`).
///
/// # Errors
/// As [`crate::locus_csv::read`] for the file; [`Error::Missing`] if the
/// log has no `FLASER` line; a malformed `FLASER`, `ODOM` or `PARAM
/// robot_frontlaser_offset` line ([`Error::Field`], [`Error::Record`])
/// naming its line and field (a `FLASER` of a beam count other than the
/// first's is refused at its `n` field).
pub fn read(path: &Path) -> Result<Carmen> {
    let file = existing(path)?;
    parse(&read_text(&file)?, &file)
}

/// One event of the log, in file order.
enum Event {
    /// A scan: its index.
    Scan(usize),
    /// A raw odometry pose (not a reset).
    Odom(Pose),
}

/// Parses the text of a CARMEN log; `path` names it in errors.
///
/// # Errors
/// As [`read`].
pub fn parse(text: &str, path: &Path) -> Result<Carmen> {
    let mut offset = 0.0;
    let mut beams: Option<u32> = None;
    let mut poses: Vec<Pose> = Vec::new();
    let mut stamps: Vec<f64> = Vec::new();
    let mut raw: Vec<f64> = Vec::new();
    let mut events: Vec<(f64, Event)> = Vec::new();
    // The line of the last FLASER, while its reset ODOM is awaited.
    let mut after_scan: Option<usize> = None;
    for mut f in records(text, path) {
        match f.next_text("kind")? {
            "PARAM" => {
                let name = f.next_text("name")?;
                if name == "robot_frontlaser_offset" {
                    offset = f.f64("value")?;
                }
            }
            "FLASER" => {
                let n = f.u32("n")?;
                if *beams.get_or_insert(n) != n || n == 0 {
                    return Err(f.field_error(
                        "n",
                        FieldProblem::OutOfRange {
                            value: n.to_string(),
                            expected: "> 0 and the beam count of the first FLASER line",
                        },
                    ));
                }
                for _ in 0..n {
                    raw.push(f.non_negative("range")?);
                }
                let pose = [f.f64("x")?, f.f64("y")?, f.f64("theta")?];
                for name in ["odom_x", "odom_y", "odom_theta", "ipc_time", "host"] {
                    f.next_text(name)?;
                }
                let stamp = f.f64("logger_time")?;
                let line = f.line;
                f.end(2 + n as usize + 9)?;
                events.push((stamp, Event::Scan(poses.len())));
                poses.push(pose);
                stamps.push(stamp);
                after_scan = Some(line);
            }
            "ODOM" => {
                let pose = [f.f64("x")?, f.f64("y")?, f.f64("theta")?];
                for name in ["tv", "rv", "accel", "ipc_time", "host"] {
                    f.next_text(name)?;
                }
                let stamp = f.f64("logger_time")?;
                // The first ODOM after a scan is its reset (the scan's
                // pose); ODOM lines before the first scan are skipped.
                if let Some(first_line) = after_scan.take() {
                    if poses.last() != Some(&pose) {
                        return Err(f.record_error(RecordProblem::Disagrees {
                            what: "the ODOM after a FLASER resets to its pose: this one differs from",
                            first_line,
                        }));
                    }
                    f.end(10)?;
                } else if !poses.is_empty() {
                    f.end(10)?;
                    events.push((stamp, Event::Odom(pose)));
                } else {
                    f.end(10)?;
                }
            }
            _ => {}
        }
    }
    let Some(n) = beams else {
        return Err(Error::Missing {
            path: path.to_path_buf(),
            what: "FLASER line",
        });
    };
    // Raw ODOM poses after the last scan carry no scan to reach.
    while matches!(events.last(), Some((_, Event::Odom(_)))) {
        events.pop();
    }
    // Non-decreasing times from the end.
    let mut retimed = 0;
    let mut largest_retime: f64 = 0.0;
    let mut next = f64::INFINITY;
    for (t, _) in events.iter_mut().rev() {
        if *t > next {
            retimed += 1;
            largest_retime = largest_retime.max(*t - next);
            *t = next;
        }
        next = *t;
    }
    let respaced = respace(&mut events);
    let sensor = BeamSensor {
        id: 0,
        mount: SensorMount {
            x: offset,
            ..SensorMount::default()
        },
        min_range: MIN_RANGE,
        max_range: MAX_RANGE,
        angle_0: ANGLE_0,
        angle_step: ANGLE_STEP,
        count: n,
    };
    let mut scans = Scans::with_capacity(poses.len(), raw.len());
    let mut scan_poses = Vec::with_capacity(poses.len());
    let mut odometry = Vec::new();
    let mut raw_motion = Vec::with_capacity(poses.len());
    let mut timeless_segments = 0;
    // The kept poses of the segment being built: (time, pose).
    let mut kept: Vec<(f64, Pose)> = Vec::new();
    // The last raw pose of the segment, whatever its time.
    let mut last: Option<Pose> = None;
    for (t, event) in &events {
        match *event {
            Event::Odom(pose) => {
                last = Some(pose);
                match kept.len() {
                    0 => {}
                    _ if *t > kept[kept.len() - 1].0 => kept.push((*t, pose)),
                    // Stamped no later than the kept pose before it: that
                    // pose is replaced (the motion to it merges into this
                    // one), unless it is the segment's start.
                    1 => {}
                    k => kept[k - 1].1 = pose,
                }
            }
            Event::Scan(i) => {
                if let Some(&(_, start)) = kept.first() {
                    let end = last.unwrap_or(start);
                    raw_motion.push(relative(start, end));
                    if kept.len() == 1 && end != start {
                        timeless_segments += 1;
                    } else {
                        // The last raw pose ends the segment even if its
                        // time merged it away.
                        let k = kept.len() - 1;
                        kept[k].1 = end;
                        segment_odometry(&kept, &mut odometry);
                    }
                }
                let pose = poses[i];
                let base = i * n as usize;
                for r in &raw[base..base + n as usize] {
                    scans.push_range(sensor.reading(*r));
                }
                scans.close(*t, 0);
                scan_poses.push(TruthPose {
                    time: *t,
                    x: pose[0],
                    y: pose[1],
                    theta: pose[2],
                });
                kept.clear();
                kept.push((*t, pose));
                last = None;
            }
        }
    }
    let log = LocusLog {
        odometry,
        // Times are non-decreasing by construction.
        truth: Groundtruth::new(scan_poses.clone()).unwrap_or_default(),
        beam_sensors: vec![sensor],
        scans,
        ..LocusLog::default()
    };
    Ok(Carmen {
        log,
        scan_poses,
        scan_stamps: stamps,
        raw_motion,
        retimed,
        largest_retime,
        respaced,
        timeless_segments,
    })
}

/// Moves each scan within [`MIN_DT`] of the scan before it to midway
/// between the scans around it, where those are at least twice [`MIN_DT`]
/// apart; the events between the two scans are spread in proportion over
/// the longer span (all to the new time if the span was empty), and the
/// events after it stamped before its new time take that time. Times stay
/// non-decreasing. Returns the scans moved.
fn respace(events: &mut [(f64, Event)]) -> usize {
    let scans: Vec<usize> = events
        .iter()
        .enumerate()
        .filter(|(_, (_, e))| matches!(e, Event::Scan(_)))
        .map(|(i, _)| i)
        .collect();
    let mut moved = 0;
    for w in scans.windows(3) {
        let (a, k, c) = (w[0], w[1], w[2]);
        let (ta, tk, tc) = (events[a].0, events[k].0, events[c].0);
        if tk - ta < MIN_DT && tc - ta >= 2.0 * MIN_DT {
            let t = 0.5 * (ta + tc);
            events[k].0 = t;
            for e in &mut events[a + 1..k] {
                e.0 = if tk > ta {
                    ta + (e.0 - ta) * (t - ta) / (tk - ta)
                } else {
                    t
                };
            }
            for e in &mut events[k + 1..c] {
                e.0 = e.0.max(t);
            }
            moved += 1;
        }
    }
    moved
}

/// Shortest chord an odometry increment spans, m, unless it ends a
/// segment: shorter motions merge into the next (the log's positions have 5
/// or 6 significant digits, so a shorter chord's direction is mostly
/// rounding, and following it exactly would take turns of absurd rates).
pub const MIN_CHORD: f64 = 0.01;

/// Shortest time an odometry increment spans, s, unless it ends a segment:
/// a shorter one merges into the next (the log has bursts of `ODOM` lines
/// 1 ms apart, and retimed stamps may be as close).
pub const MIN_DT: f64 = 0.1;

/// Appends the odometry records of one segment's kept poses (at least two,
/// times increasing), then a record of zero speeds at its last time.
fn segment_odometry(kept: &[(f64, Pose)], out: &mut Vec<Odometry>) {
    let mut nodes = vec![kept[0]];
    for (i, &(t, p)) in kept.iter().enumerate().skip(1) {
        let (t0, from) = nodes[nodes.len() - 1];
        let [lx, ly, _] = relative(from, p);
        if lx.hypot(ly) >= MIN_CHORD && t - t0 >= MIN_DT {
            nodes.push((t, p));
        } else if i + 1 == kept.len() {
            // The segment's last pose: it extends the last increment, or
            // is the only one.
            if nodes.len() > 1 {
                let k = nodes.len() - 1;
                nodes[k] = (t, p);
            } else {
                nodes.push((t, p));
            }
        }
    }
    let kept = &nodes[..];
    for w in kept.windows(2) {
        let ((t0, a), (t1, b)) = (w[0], w[1]);
        let dt = t1 - t0;
        let [lx, ly, dth] = relative(a, b);
        let chord = lx.hypot(ly);
        if chord == 0.0 {
            out.push(Odometry {
                time: t0,
                v: 0.0,
                omega: dth / dt,
            });
            continue;
        }
        // The chord's direction, and its sign: backwards when it points
        // more than a right angle from the arc's direction.
        let mut alpha = ly.atan2(lx);
        let mut signed = chord;
        if wrap(alpha - dth / 2.0).abs() > core::f64::consts::FRAC_PI_2 {
            alpha = wrap(alpha + core::f64::consts::PI);
            signed = -chord;
        }
        let phi = wrap(2.0 * alpha - dth);
        if phi.abs() <= 1e-12 {
            out.push(Odometry {
                time: t0,
                v: signed / (dt * sinc(dth / 2.0)),
                omega: dth / dt,
            });
        } else {
            let half = dt / 2.0;
            let turn = dth - phi;
            out.push(Odometry {
                time: t0,
                v: 0.0,
                omega: phi / half,
            });
            out.push(Odometry {
                time: t0 + half,
                v: signed / (half * sinc(turn / 2.0)),
                omega: turn / half,
            });
        }
    }
    if let Some(&(t, _)) = kept.last() {
        out.push(Odometry {
            time: t,
            v: 0.0,
            omega: 0.0,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::se2::dead_reckon;

    fn p() -> &'static Path {
        Path::new("intel.log")
    }

    /// A log of three 2-beam scans (beams at -90 and -89 degrees, not the
    /// Intel log's 180): raw odometry before the first scan (skipped), an
    /// ODOM stamped before its scan, and a burst of ODOM lines 1 ms apart.
    const LOG: &str = "# CARMEN\nPARAM robot_frontlaser_offset 0.05 nohost 0\n\
        ODOM 0 0 0 0 0 0 0.5 pippo 0.5\n\
        FLASER 2 1.5 81.83 1 2 0.5 1 2 0.5 1 pippo 1\n\
        ODOM 1 2 0.5 0 0 0 0 pippo 0\nNEFF 15\n\
        ODOM 1.1 2.05 0.55 0 0 0 0.9 pippo 0.9\n\
        ODOM 1.3 2.1 0.6 0 0 0 1.5 pippo 1.5\n\
        ODOM 1.31 2.1 0.6 0 0 0 1.501 pippo 1.501\n\
        ODOM 1.5 2.2 0.4 0 0 0 2 pippo 2\n\
        FLASER 2 2 3 1.6 2.1 0.45 1.6 2.1 0.45 2 pippo 2\n\
        ODOM 1.6 2.1 0.45 0 0 0 0 pippo 0\n\
        ODOM 1.6 2.1 0.5 0 0 0 2.5 pippo 2.5\n\
        FLASER 2 2 3 1.7 2.1 0.5 1.7 2.1 0.5 3 pippo 3\n\
        ODOM 1.7 2.1 0.5 0 0 0 0 pippo 0\nODOM 9 9 9 0 0 0 4 pippo 4\n";

    /// The odometry of `c` dead-reckons each scan-to-scan raw motion
    /// exactly (to 1e-12).
    fn assert_dead_reckons(c: &Carmen) {
        let times = c.log.scans.times();
        for (k, want) in c.raw_motion.iter().enumerate() {
            let got = dead_reckon(&c.log.odometry, times[k], times[k + 1]);
            for i in 0..3 {
                assert!((got[i] - want[i]).abs() < 1e-12, "{k}: {got:?} {want:?}");
            }
        }
    }

    #[test]
    fn scans_truth_and_odometry_that_dead_reckons_the_raw_motion() {
        let c = parse(LOG, p()).unwrap();
        let log = &c.log;
        assert_eq!(log.scans.len(), 3);
        assert_eq!(c.scan_stamps, [1.0, 2.0, 3.0]);
        assert_eq!(log.beam_sensors[0].mount.x, 0.05);
        assert_eq!(log.beam_sensors[0].count, 2);
        let first = log.scans.get(0).unwrap();
        assert_eq!(first.ranges, [1.5, crate::scans::NO_RETURN]);
        assert_eq!(log.truth.poses()[1].x, 1.6);
        // The ODOM stamped 0.9 pulls its scan back from 1 s.
        assert_eq!(log.scans.times(), [0.9, 2.0, 3.0]);
        assert_eq!((c.retimed, c.largest_retime), (1, 0.09999999999999998));
        assert_eq!(c.raw_motion.len(), 2);
        assert_dead_reckons(&c);
        // Nothing after the last scan, nothing before the first.
        assert!(log.odometry.iter().all(|o| (0.9..=3.0).contains(&o.time)));
        assert_eq!(c.timeless_segments, 0);
        assert_eq!(c.respaced, 0);
    }

    /// A scan stamped after the next one is pulled back to 10 ms after the
    /// scan before it; it moves to midway between its neighbours, the
    /// turn before it spans that time, and dead reckoning still reaches
    /// each scan's raw motion.
    #[test]
    fn a_scan_squeezed_against_the_one_before_moves_midway() {
        let squeezed = "FLASER 2 1 1 0 0 0 0 0 0 1 h 1\n\
            ODOM 0 0 0 0 0 0 0 h 0\n\
            ODOM 0.05 0 0.3 0 0 0 1.5 h 1.5\n\
            ODOM 0.1 0 0.6 0 0 0 1.9 h 1.9\n\
            FLASER 2 1 1 0.1 0 0.6 0.1 0 0.6 2.5 h 2.5\n\
            ODOM 0.1 0 0.6 0 0 0 0 h 0\n\
            ODOM 0.2 0.05 0.6 0 0 0 1.01 h 1.01\n\
            ODOM 0.3 0.1 0.6 0 0 0 2.9 h 2.9\n\
            FLASER 2 1 1 0.3 0.1 0.6 0.3 0.1 0.6 3 h 3\n";
        let c = parse(squeezed, p()).unwrap();
        let times = c.log.scans.times().to_vec();
        // Pulled back to 1.01 s (the ODOM after it), then moved midway
        // between 1 s and 3 s.
        assert_eq!(times, [1.0, 2.0, 3.0]);
        assert_eq!(c.respaced, 1);
        // 0.6 rad and 0.1 m over a second, not 10 ms: within a replay's
        // generic limits (locus_models::plausible::Limits::GENERIC, 4 pi
        // rad/s and 10 m/s; before the move, a turn of 120 rad/s).
        for o in &c.log.odometry {
            assert!(
                o.omega.abs() < 4.0 * core::f64::consts::PI && o.v.abs() < 10.0,
                "{o:?}"
            );
        }
        assert_dead_reckons(&c);
    }

    #[test]
    fn malformed_logs_name_the_line_and_field() {
        let e = parse("ODOM 0 0 0 0 0 0 1 h 1\n", p()).unwrap_err();
        assert_eq!(e.to_string(), "intel.log: no FLASER line");
        let e = parse(
            "FLASER 2 1 1 0 0 0 0 0 0 1 h 1\nFLASER 3 1 1 1 0 0 0 0 0 0 2 h 2\n",
            p(),
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "intel.log:2: field \"n\" (column 2): 3 is out of range: \
             > 0 and the beam count of the first FLASER line"
        );
        let e = parse("FLASER 2 1 -1 0 0 0 0 0 0 1 h 1\n", p()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "intel.log:1: field \"range\" (column 4): -1 is out of range: >= 0"
        );
        let e = parse("FLASER 2 1 1 0 0 0 0 0 0 1 h\n", p()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "intel.log:1: field \"logger_time\" (column 13): missing"
        );
        let e = parse(
            "FLASER 1 1 0 0 0 0 0 0 1 h 1\n\nODOM 0 1 0 0 0 0 0 h 0\n",
            p(),
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "intel.log:3: the ODOM after a FLASER resets to its pose: this one differs from line 1"
        );
    }
}
