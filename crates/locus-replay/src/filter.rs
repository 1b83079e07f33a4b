//! The replay's filter and how one event is applied to it.
//!
//! The state ([`STATE`] = 8) is the pose `x`, `y` (m), `theta` (rad) and
//! the calibration of
//! [`CalibratedUnicycle`](locus_models::calibrated_unicycle::CalibratedUnicycle):
//! speed scale `s_v`, turn-rate scale `s_omega`, turn-rate bias `b_omega`
//! (rad/s), bearing bias `b_bearing` (rad), and the beams' range bias
//! `b_range` (m). The running filter's track
//! carries beside it the input in force and dead reckoning ([`Carried`]);
//! its history holds at most [`HISTORY`] events.
//!
//! [`apply`] is the running filter's deterministic `apply`: it predicts
//! the track over the time since its last event with the input then in
//! force, then takes the event (an odometry record sets the input; a
//! sighting is one Student-t range-bearing or range-only correction,
//! refused without changing the track if the filter cannot use it) and
//! records the sighting's innovation log-likelihood term, its NIS capped
//! at [`NIS_CAP`] or [`NIS_CAP_RANGE`].

use locus_core::nalgebra::{SMatrix, SVector, Vector2, Vector3};
use locus_core::{
    Belief, MeasurementModel, MotionModel, Rules, RunningFilter, StudentT, Track, Update,
};
use locus_models::calibrated_range::CalibratedRange;
use locus_models::calibrated_range_bearing::CalibratedRangeBearing;
use locus_models::calibrated_unicycle::{BEARING_BIAS, OMEGA_BIAS, OMEGA_SCALE, V_SCALE};
use locus_models::range_bearing::RangeBearing;
use locus_models::unicycle::{Unicycle, Velocities};

use crate::beam::{Beam, beam};
use crate::event::{Entry, Event};
use crate::{Config, Log, ScanOutcome, SightingOutcome, Unusable};

/// Cap on one sighting's NIS in
/// [`Report::innovation_nll`](crate::Report::innovation_nll): the 99.9 %
/// point of chi-square with 2 degrees of freedom, `-2 ln 0.001`.
pub const NIS_CAP: f64 = 13.815_510_557_964_274;

/// Cap on a range-only sighting's NIS in
/// [`Report::innovation_nll`](crate::Report::innovation_nll): the 99.9 %
/// point of chi-square with 1 degree of freedom.
pub const NIS_CAP_RANGE: f64 = 10.827_566_170_662_733;

/// What the replay carries beside the belief: the input in force (scaled)
/// and dead reckoning from the same start with the same inputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Carried {
    pub(crate) v: f64,
    pub(crate) omega: f64,
    pub(crate) dead: Vector3<f64>,
}

/// Dimension of the replay's state: the pose, the calibration and the range
/// bias of
/// [`CalibratedUnicycle`](locus_models::calibrated_unicycle::CalibratedUnicycle).
pub use locus_models::calibrated_unicycle::STATE;

/// The replay's state vector and covariance.
pub type StateVector = SVector<f64, STATE>;
/// A covariance of the replay's state.
pub type StateMatrix = SMatrix<f64, STATE, STATE>;

/// Events the history holds at most. The history is cut by time
/// ([`Config::horizon`]); this bound only matters for a log with more than
/// this many events within one horizon, whose oldest events then become
/// final early.
pub(crate) const HISTORY: usize = 1024;

pub(crate) type Filter = RunningFilter<f64, STATE, HISTORY, Entry, Carried>;
pub(crate) type State = Track<f64, STATE, Carried>;

/// Advances `track` to `entry`'s time and applies it (the running filter's
/// `apply`; deterministic, as a re-run needs).
pub(crate) fn apply(
    cfg: &Config,
    log: &Log,
    rules: &Rules<f64>,
    track: &mut State,
    entry: &mut Entry,
) -> Result<(), locus_core::Error> {
    let t = entry.event.time();
    let dt = t - track.time;
    if dt > 0.0 {
        let model = cfg.motion_model();
        let c = track.extra;
        let u = Velocities {
            v: c.v,
            omega: c.omega,
            dt,
        };
        track.predict(&rules.ekf, &model, &u)?;
        track.extra.dead = Unicycle::new(0.0, 0.0).f(&c.dead, &u, &Vector2::zeros());
        track.time = t;
    }
    entry.inflations = 0;
    entry.nll = 0.0;
    entry.scan = ScanOutcome::default();
    entry.outcome = match entry.event {
        Event::Scan(scan, _) => {
            scan_correct(cfg, log, rules, track, entry, scan.index)?;
            None
        }
        Event::Odometry(o, _) => {
            track.extra.v = o.v;
            track.extra.omega = o.omega;
            None
        }
        Event::Sighting(z, _) => Some(match log.landmark(z.landmark) {
            None => SightingOutcome::NotInMap,
            // Also NaN, should a log ever hold one.
            Some(_) if z.range.is_nan() || z.range > cfg.max_range => {
                SightingOutcome::Unusable(Unusable::RangeAbove { max: cfg.max_range })
            }
            Some(l) => {
                let inner = RangeBearing::new(
                    Vector2::new(l.x, l.y),
                    Vector2::new(log.sensor.x, log.sensor.y),
                    cfg.sigma_range,
                    cfg.sigma_bearing,
                );
                let outcome = match z.bearing {
                    Some(bearing) => correct(
                        cfg,
                        rules,
                        track,
                        entry,
                        &CalibratedRangeBearing {
                            inner,
                            yaw: log.sensor.yaw,
                        },
                        &Vector2::new(z.range, bearing),
                        NIS_CAP,
                        SMatrix::determinant,
                    ),
                    None => correct(
                        cfg,
                        rules,
                        track,
                        entry,
                        &CalibratedRange { inner },
                        &SVector::<f64, 1>::new(z.range),
                        NIS_CAP_RANGE,
                        |s| s[(0, 0)],
                    ),
                };
                match outcome? {
                    Some(o) => o,
                    // Refused: the track is unchanged.
                    None => return Ok(()),
                }
            }
        }),
    };
    Ok(())
}

/// Corrects `track` with scan `index` of the log, one chosen beam after
/// the other (papers 000/003: each beam one scalar update), or as paper
/// 001's IR pair if the log declares its sensor one (`ir_pair.rs`): the beam cast
/// in the log's map from the current estimate gives the surface it should
/// see, [`PlanarBeam`](locus_models::planar_beam::PlanarBeam) the range to it and its Jacobian. A beam with no
/// return, no surface in range (or one met grazing), or a reading far
/// shorter than the map's (something not in the map) is skipped; the rest
/// are Student-t weighted and gated as sightings are, with no covariance
/// inflation (one scan's many beams are not a run of rejections). The
/// scan's innovation log-likelihood term is the sum of its beams'.
fn scan_correct(
    cfg: &Config,
    log: &Log,
    rules: &Rules<f64>,
    track: &mut State,
    entry: &mut Entry,
    index: usize,
) -> Result<(), locus_core::Error> {
    use locus_logs::scans::Reading;
    let (Some(scan), Some(map)) = (log.scans.get(index), log.map.as_deref()) else {
        return Ok(());
    };
    let Some(sensor) = log.beam_sensors.iter().find(|b| b.id == scan.sensor) else {
        return Ok(());
    };
    let beams = cfg.beams;
    let rules = Rules {
        recovery: None,
        ..*rules
    };
    if let Some(pair) = crate::ir_pair::pair_of(log, index) {
        entry.nll = crate::ir_pair::correct(cfg, log, &rules, track, &mut entry.scan, index, pair)?;
        return Ok(());
    }
    let robust = cfg.robust_dof.and_then(|dof| StudentT::new(dof).ok());
    let count = scan.ranges.len();
    let out = &mut entry.scan;
    out.beams = u32::try_from(count).unwrap_or(u32::MAX);
    out.chosen = u32::try_from(count.min(beams.per_scan as usize)).unwrap_or(u32::MAX);
    // The scan aligned to the map (`scan_align.rs`): its beams are then
    // cast from the aligned state and linearised there (the iterated EKF,
    // `linearised_at.rs`); a scan that cannot be aligned is cast and
    // linearised at the running estimate, beam after beam.
    let aligned = crate::scan_align::align(
        &crate::scan_align::ScanBeams {
            map,
            sensor,
            ranges: scan.ranges,
            per_scan: beams.per_scan,
        },
        &track.belief.x,
        &track.belief.p,
        &beams,
        cfg.robust_dof,
    )
    .map(|a| {
        let mut from = track.belief.x;
        from.fixed_rows_mut::<3>(0).copy_from(&a.pose);
        from
    });
    let mut nll = 0.0;
    for k in chosen_beams(count, beams.per_scan) {
        let z = match Reading::of(scan.ranges[k]) {
            Reading::Range(r) => f64::from(r),
            Reading::NoReturn | Reading::Missing => {
                out.no_return += 1;
                continue;
            }
        };
        let x = track.belief.x;
        let from = aligned.as_ref().unwrap_or(&x);
        out.aligned = u32::from(aligned.is_some());
        let model = match beam(map, sensor, k, z, from, &x, &track.belief.p, &beams) {
            Beam::NoSurface => {
                out.no_surface += 1;
                continue;
            }
            Beam::Short { .. } => {
                out.short += 1;
                continue;
            }
            Beam::Usable { model, .. } => model,
        };
        let zv = SVector::<f64, 1>::new(z);
        let update = match robust {
            Some(t) => track.correct_robust(&rules, &t, &model, &zv),
            None => track.correct(&rules, &model, &zv),
        };
        let update = match update {
            Ok(u) => u,
            Err(e) if Unusable::of(e).is_some() => {
                out.unusable += 1;
                continue;
            }
            Err(e) => return Err(e),
        };
        if let Some(first) = update.first_attempt() {
            nll += 0.5 * first.s[(0, 0)].ln() + 0.5 * first.nis.min(NIS_CAP_RANGE);
        }
        match update {
            Update::Applied {
                correction, weight, ..
            } => {
                out.applied += 1;
                out.down_weighted += u32::from(weight < 1.0);
                out.nis += correction.nis;
            }
            Update::Gated { correction, .. } => {
                out.gated += 1;
                out.nis += correction.nis;
            }
            Update::NoMeasurement => out.no_surface += 1,
        }
    }
    entry.nll = nll;
    Ok(())
}

/// The beams of a scan of `count` beams that a replay spends, `per_scan`
/// at most: the middle beam of each of that many equal parts.
pub(crate) fn chosen_beams(count: usize, per_scan: u32) -> impl Iterator<Item = usize> {
    let chosen = count.min(per_scan as usize);
    (0..chosen).map(move |j| (2 * j + 1) * count / (2 * chosen))
}

/// Corrects `track` with one sighting `z` of `M` components (range and
/// bearing, or range alone) by `model`, Student-t weighted as `cfg` says,
/// and records its innovation log-likelihood term (its NIS capped at
/// `nis_cap`; `determinant` of the innovation covariance) in `entry`. `Ok(None)`: the correction failed on the
/// sighting, which is refused (`entry`'s outcome set, the track unchanged).
fn correct<const M: usize>(
    cfg: &Config,
    rules: &Rules<f64>,
    track: &mut State,
    entry: &mut Entry,
    model: &impl MeasurementModel<f64, STATE, M>,
    z: &SVector<f64, M>,
    nis_cap: f64,
    determinant: fn(&SMatrix<f64, M, M>) -> f64,
) -> Result<Option<SightingOutcome>, locus_core::Error> {
    let update = match cfg.robust_dof.map(StudentT::new) {
        Some(Ok(t)) => track.correct_robust(rules, &t, model, z),
        _ => track.correct(rules, model, z),
    };
    // A correction that fails on the sighting (not on the belief) refuses
    // it; the track is then unchanged.
    let update = match update {
        Ok(u) => u,
        Err(e) => match Unusable::of(e) {
            Some(why) => {
                entry.outcome = Some(SightingOutcome::Unusable(why));
                return Ok(None);
            }
            None => return Err(e),
        },
    };
    if let Some(first) = update.first_attempt() {
        entry.nll = 0.5 * determinant(&first.s).ln() + 0.5 * first.nis.min(nis_cap);
    }
    entry.inflations = u32::from(update.inflated());
    Ok(Some(match update {
        Update::Applied {
            correction,
            first,
            weight,
        } => SightingOutcome::Applied {
            nis: correction.nis,
            recovered: first.is_some(),
            weight,
        },
        Update::Gated { correction, .. } => SightingOutcome::Gated {
            nis: correction.nis,
        },
        Update::NoMeasurement => SightingOutcome::NoMeasurement,
    }))
}

/// The pose part of a belief of the replay's state.
pub(crate) fn pose_belief(b: &Belief<f64, STATE>) -> Belief<f64, 3> {
    Belief::new(
        b.x.fixed_rows::<3>(0).into_owned(),
        b.p.fixed_view::<3, 3>(0, 0).into_owned(),
    )
}

/// The calibration part of a belief: `(mean, standard deviation)` of `s_v`,
/// `s_omega`, `b_omega` (rad/s) and `b_bearing` (rad).
pub(crate) fn calibration_of(b: &Belief<f64, STATE>) -> [(f64, f64); 4] {
    [V_SCALE, OMEGA_SCALE, OMEGA_BIAS, BEARING_BIAS].map(|i| (b.x[i], b.p[(i, i)].sqrt()))
}

#[cfg(test)]
mod nis_caps {
    /// The caps are the 99.9 % points of chi-square with 2 and 1 dof.
    #[test]
    fn the_caps_are_the_chi_square_points() {
        for (cap, dof) in [(super::NIS_CAP, 2), (super::NIS_CAP_RANGE, 1)] {
            let q = locus_core::chi2::quantile(0.999, dof).unwrap();
            assert!((cap - q).abs() < 1e-9 * q, "{cap} against {q} ({dof} dof)");
        }
    }
}
