//! The ground truth's clock against the robot's sensors.
//!
//! A motion-capture system stamps its poses on its own clock; a log that
//! puts them beside the robot's readings may have them late or early by
//! tens of milliseconds (transport, filtering, a clock set apart). Compared
//! at its stamps, such a truth charges the estimate with the robot's speed
//! times the offset, an error no estimator of the robot can remove, and
//! its 3-sigma shares then judge the truth's clock rather than the filter.
//!
//! The offset is measured from the sensors alone, not from any estimate:
//! each range reading (a beam's, cast in the map, or a sighting's) is
//! predicted from the truth's pose at its time plus a trial offset
//! ([`OFFSETS`]), and the offset whose residuals have the smallest robust
//! spread (the median absolute deviation about their median, so a range
//! bias does not count) is the truth's. It is applied only where it is
//! decisive: the spread at it at most [`DECISIVE`] of the spread at the
//! stamps (a clock offset worth correcting dominates the residuals; a
//! few per cent is within what the choice of readings moves it). A long
//! log is read at an even stride, [`MAX_EVENTS`] scans and as many
//! sightings at most.

use alloc::vec::Vec;

use locus_core::MeasurementModel;
use locus_core::nalgebra::{Vector2, Vector3};
use locus_logs::scans::Reading;
use locus_models::range_bearing::RangeBearing;

use crate::{Config, Log, StateVector};

/// The trial offsets, s: -0.5 to 0.5 s in steps of 10 ms.
pub const OFFSETS: core::ops::RangeInclusive<i32> = -50..=50;
/// Seconds per step of [`OFFSETS`].
pub const STEP: f64 = 0.01;
/// The spread at the best offset, as a share of the spread at the stamps,
/// at most which the offset is applied.
pub const DECISIVE: f64 = 0.75;
/// Readings the measurement needs at least.
pub const MIN_READINGS: usize = 50;
/// Scans, and sightings, the measurement reads at most: a longer log is
/// read at an even stride (each trial offset reads them all again).
pub const MAX_EVENTS: usize = 2000;

/// The truth's clock, as measured and as applied.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthClock {
    /// How late the truth's stamps are against the sensors, s: the truth
    /// stamped `t + offset` is the robot at `t`.
    pub offset: f64,
    /// Whether the truth is compared at `offset` (else at its stamps).
    pub applied: bool,
    /// Whether `offset` was given (not measured).
    pub given: bool,
    /// The residuals' spread at the stamps and at `offset`, m (NaN when
    /// given).
    pub spread: [f64; 2],
    /// Range readings measured.
    pub readings: usize,
}

/// The range residuals of `log`'s readings against its truth moved by
/// `offset` (s), as readings at `time` see the truth at `time + offset`.
fn residuals(log: &Log, cfg: &Config, offset: f64, out: &mut Vec<f64>) {
    out.clear();
    let gap = cfg.truth_max_gap;
    let mut truth = log.truth.cursor();
    if let Some(map) = log.map.as_deref() {
        let stride = log.scans.len().div_ceil(MAX_EVENTS).max(1);
        for scan in log.scans.iter().step_by(stride) {
            let Some(sensor) = log.beam_sensors.iter().find(|b| b.id == scan.sensor) else {
                continue;
            };
            let Some(t) = truth.pose_at(scan.time + offset, gap) else {
                continue;
            };
            let theta = if t.theta.is_nan() { 0.0 } else { t.theta };
            let mut x = StateVector::zeros();
            x[0] = t.x;
            x[1] = t.y;
            x[2] = theta;
            for k in crate::filter::chosen_beams(scan.ranges.len(), cfg.beams.per_scan) {
                let Reading::Range(z) = Reading::of(scan.ranges[k]) else {
                    continue;
                };
                let Some(model) = crate::beam::beam_model(map, sensor, k, &x, &cfg.beams) else {
                    continue;
                };
                if let Some(h) = model.h(&x) {
                    out.push(f64::from(z) - h[0]);
                }
            }
        }
    }
    let mut truth = log.truth.cursor();
    let sensor = Vector2::new(log.sensor.x, log.sensor.y);
    let stride = log.sightings.len().div_ceil(MAX_EVENTS).max(1);
    for z in log.sightings.iter().step_by(stride) {
        let (Some(l), Some(t)) = (
            log.landmark(z.landmark),
            truth.pose_at(z.time + offset, gap),
        ) else {
            continue;
        };
        let model = RangeBearing::new(Vector2::new(l.x, l.y), sensor, 1.0, 1.0);
        let theta = if t.theta.is_nan() { 0.0 } else { t.theta };
        if let Some(h) = model.h(&Vector3::new(t.x, t.y, theta)) {
            out.push(z.range - h[0]);
        }
    }
}

/// Median absolute deviation about the median (sorts `v`).
fn mad(v: &mut [f64]) -> f64 {
    let median = |v: &mut [f64]| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let m = median(v);
    for x in v.iter_mut() {
        *x = (*x - m).abs();
    }
    median(v)
}

/// Measures the truth's clock of `log` (the module documentation). `None`
/// for a log without truth or with fewer than [`MIN_READINGS`] readings
/// it can predict.
#[must_use]
pub fn measure(log: &Log, cfg: &Config) -> Option<TruthClock> {
    if log.truth.poses().is_empty() {
        return None;
    }
    let mut buf = Vec::new();
    let mut spread_at = |offset: f64| {
        residuals(log, cfg, offset, &mut buf);
        (buf.len() >= MIN_READINGS).then(|| (mad(&mut buf), buf.len()))
    };
    let (at_zero, readings) = spread_at(0.0)?;
    let mut best = (0.0, at_zero);
    for k in OFFSETS {
        let offset = f64::from(k) * STEP;
        if let Some((s, _)) = spread_at(offset)
            && s < best.1
        {
            best = (offset, s);
        }
    }
    Some(TruthClock {
        offset: best.0,
        applied: best.1 <= DECISIVE * at_zero,
        given: false,
        spread: [at_zero, best.1],
        readings,
    })
}

/// Puts `log`'s truth on the sensors' clock: by `given` (s) if given, else
/// by the offset [`measure`] finds where it is decisive. Returns what was
/// done (`None`: a log without truth or readings to measure it by, left
/// as it is).
pub fn settle(log: &mut Log, cfg: &Config, given: Option<f64>) -> Option<TruthClock> {
    let clock = match given {
        Some(offset) => TruthClock {
            offset,
            applied: offset != 0.0,
            given: true,
            spread: [f64::NAN; 2],
            readings: 0,
        },
        None => measure(log, cfg)?,
    };
    if clock.applied {
        log.truth = log.truth.shifted(-clock.offset);
    }
    Some(clock)
}

impl core::fmt::Display for TruthClock {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let mm = |v: f64| v * 1000.0;
        match (self.given, self.applied) {
            (true, true) => write!(
                f,
                "truth compared {:+.3} s from its stamps (given)",
                self.offset
            ),
            (true, false) => f.write_str("truth compared at its stamps (given)"),
            (false, true) => write!(
                f,
                "truth compared {:+.3} s from its stamps: its clock is that late against the \
                 sensors ({} range readings predicted from it spread {:.1} mm there, {:.1} mm \
                 at the stamps; --truth-offset 0 compares at the stamps)",
                self.offset,
                self.readings,
                mm(self.spread[1]),
                mm(self.spread[0])
            ),
            (false, false) => write!(
                f,
                "truth compared at its stamps (its best offset, {:+.3} s, moves the {} range \
                 readings' spread only from {:.1} to {:.1} mm)",
                self.offset,
                self.readings,
                mm(self.spread[0]),
                mm(self.spread[1])
            ),
        }
    }
}
