//! Paper 001's IR pair in a log's replay: the two sensors' readings of one
//! instant corrected as one 2-D measurement of the wall they face (paper
//! 001, eq. 3-5, 17-20), as its closed loop does
//! ([`Localiser::ir`](locus_models::Localiser::ir)), rather than as two
//! beams one after the other.
//!
//! The pair's scans of one instant are taken at the scan of the pair's
//! lower sensor id (the canonical order puts it first). There:
//!
//! * both sensors must read; a lone reading is not used (the pair's
//!   measurement needs both), and is counted as unusable;
//! * the readings are associated as paper 001 does
//!   ([`associate_ir_wall`](locus_models::associate_ir_wall)): the ray from
//!   the pair's centre, to the robot's right, is cast in the log's walls
//!   from the running estimate within the pair's association range; the
//!   wall it meets, if axis-aligned ([`axis_wall`]), is the one observed.
//!   Otherwise both beams count as meeting no surface;
//! * the measurement [`IrPairObservation`] (noise `V R V^T` with `R =
//!   sigma_beam^2` for each sensor) corrects the pose ([`OnPose`]: the
//!   calibration does not enter it), Student-t weighted and gated as the
//!   beams are, with 2 degrees of freedom.
//!
//! The scan of the other sensor at that instant counts no beams: both are
//! counted on the first. A map of occupancy cells has no walls to
//! associate with: there the pair's sensors are corrected beam by beam.

use locus_core::nalgebra::SMatrix;
use locus_core::{Rules, StudentT, Update};
use locus_logs::IrPairRecord;
use locus_logs::scans::Reading;
use locus_map::{HitSource, Map, SegmentMap};
use locus_models::on_pose::OnPose;
use locus_models::{IrPair, IrPairObservation, axis_wall};

use crate::filter::{NIS_CAP, State};
use crate::{Config, Log, ScanOutcome, Unusable};

/// The IR pair scan `index` belongs to, if its sensor is one of a pair,
/// with the log's walls (the pair's association needs walls; a map of
/// cells has none).
pub(crate) fn pair_of(log: &Log, index: usize) -> Option<(&IrPairRecord, &SegmentMap)> {
    let sensor = log.scans.get(index)?.sensor;
    let Some(Map::Segments(walls)) = log.map.as_deref() else {
        return None;
    };
    let pair = log
        .ir_pairs
        .iter()
        .find(|p| p.front == sensor || p.rear == sensor)?;
    Some((pair, walls))
}

/// Corrects `track` with the pair `pair` at its scan `index` (module doc);
/// returns the innovation log-likelihood term (0 if nothing was judged).
pub(crate) fn correct(
    cfg: &Config,
    log: &Log,
    rules: &Rules<f64>,
    track: &mut State,
    out: &mut ScanOutcome,
    index: usize,
    (pair, walls): (&IrPairRecord, &SegmentMap),
) -> Result<f64, locus_core::Error> {
    let Some(scan) = log.scans.get(index) else {
        return Ok(0.0);
    };
    if scan.sensor != pair.front.min(pair.rear) {
        // Counted with its partner's scan.
        return Ok(0.0);
    }
    // The reading of `sensor` at the scan's time, from the scans of that
    // time around `index`.
    let reading = |sensor: u32| {
        let same_time = |i: &usize| log.scans.times().get(*i) == Some(&scan.time);
        let at = (index..log.scans.len())
            .take_while(same_time)
            .chain((0..index).rev().take_while(same_time))
            .find(|&i| log.scans.get(i).is_some_and(|s| s.sensor == sensor))?;
        match Reading::of(*log.scans.get(at)?.ranges.first()?) {
            Reading::Range(r) => Some(f64::from(r)),
            Reading::NoReturn | Reading::Missing => None,
        }
    };
    let (Some(front), Some(rear)) = (
        log.beam_sensors.iter().find(|b| b.id == pair.front),
        log.beam_sensors.iter().find(|b| b.id == pair.rear),
    ) else {
        return Ok(0.0);
    };
    out.beams = 2;
    out.chosen = 2;
    let (ds1, ds2) = match (reading(pair.front), reading(pair.rear)) {
        (Some(a), Some(b)) => (a, b),
        (a, b) => {
            let read = u32::from(a.is_some()) + u32::from(b.is_some());
            out.no_return += 2 - read;
            out.unusable += read;
            return Ok(0.0);
        }
    };
    let (spacing, lateral_offset, forward_offset) = IrPairRecord::geometry(front, rear);
    let geometry = IrPair {
        spacing,
        lateral_offset,
        forward_offset,
    };
    let x = track.belief.x;
    let (origin, dir) = geometry.sensing_ray(&x.fixed_rows::<3>(0).into_owned());
    let wall = walls
        .cast(
            origin.into(),
            x[2] - core::f64::consts::FRAC_PI_2,
            pair.association_range,
        )
        .and_then(|hit| match hit.source {
            HitSource::Segment(i) => walls.segments().get(i).copied(),
            HitSource::Cell(_) => None,
        })
        .and_then(|seg| {
            let [x1, y1, x2, y2]: [f64; 4] = seg.into();
            axis_wall([x1, y1], [x2, y2], &dir)
        });
    let Some(wall) = wall else {
        out.no_surface += 2;
        return Ok(0.0);
    };
    let var = cfg.beams.sigma * cfg.beams.sigma;
    let observation = IrPairObservation {
        pair: geometry,
        wall,
        ds1,
        ds2,
        r11: var,
        r22: var,
    };
    let model = OnPose(observation);
    let z = observation.z();
    let update = match cfg.robust_dof.and_then(|dof| StudentT::new(dof).ok()) {
        Some(t) => track.correct_robust(rules, &t, &model, &z),
        None => track.correct(rules, &model, &z),
    };
    let update = match update {
        Ok(u) => u,
        Err(e) if Unusable::of(e).is_some() => {
            out.unusable += 2;
            return Ok(0.0);
        }
        Err(e) => return Err(e),
    };
    let nll = update.first_attempt().map_or(0.0, |first| {
        0.5 * SMatrix::determinant(&first.s).ln() + 0.5 * first.nis.min(NIS_CAP)
    });
    match update {
        Update::Applied {
            correction, weight, ..
        } => {
            out.applied += 2;
            out.down_weighted += 2 * u32::from(weight < 1.0);
            out.nis += correction.nis;
        }
        Update::Gated { correction, .. } => {
            out.gated += 2;
            out.nis += correction.nis;
        }
        Update::NoMeasurement => out.no_surface += 2,
    }
    Ok(nll)
}
