//! The Monte Carlo reproduction of Table III ([`table3`]).

use super::config::{INSTANTS, LaserModel, Wall45Config};
use super::record::Wall45Record;
use super::run::run_wall45;
use crate::closed_loop::Error;
use locus_eval::Sample;

/// Monte Carlo figures of one Table III instant for one laser model (SI:
/// m, rad).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InstantStats {
    /// Mean true pose `[x, y, theta]` over the runs (m, m, rad).
    pub truth: [f64; 3],
    /// Mean EKF estimate `[x, y, theta]` (m, m, rad; heading as the mean
    /// of wrapped errors subtracted from the mean truth).
    pub estimate: [f64; 3],
    /// EKF position RMSE over the runs (m).
    pub position_rmse: f64,
    /// EKF heading RMSE (rad).
    pub heading_rmse: f64,
    /// Mean NEES (3 dof; 3 for a consistent filter).
    pub mean_nees: f64,
    /// Odometry-alone position RMSE (m).
    pub odometry_position_rmse: f64,
    /// Odometry-alone heading RMSE (rad).
    pub odometry_heading_rmse: f64,
}

/// The Monte Carlo reproduction of Table III: per instant, per model.
#[derive(Debug, Clone, PartialEq)]
pub struct Table3 {
    /// Runs (seeds) per model.
    pub runs: usize,
    /// The six instants with the paper's `H` ([`LaserModel::Paper`]).
    pub paper_h: [InstantStats; INSTANTS],
    /// The six instants with the exact model ([`LaserModel::Exact`]).
    pub exact: [InstantStats; INSTANTS],
}

/// The six instants' samples of one run.
fn instants_of_run(cfg: &Wall45Config, seed: u64) -> Result<[Sample; INSTANTS], Error> {
    let mut out = [Sample::default(); INSTANTS];
    let mut seen = 0usize;
    run_wall45(cfg, seed, &mut |r: &Wall45Record| {
        if let Some(i) = r.instant {
            out[i - 1] = r.sample;
            seen += 1;
        }
    })?;
    if seen == INSTANTS {
        Ok(out)
    } else {
        Err(Error::Config(
            "dwell must give at least one step per instant",
        ))
    }
}

/// Accumulates the runs' samples of each instant into [`InstantStats`].
#[allow(clippy::cast_precision_loss)]
fn stats(runs: &[[Sample; INSTANTS]]) -> [InstantStats; INSTANTS] {
    let n = runs.len().max(1) as f64;
    let mut out = [InstantStats::default(); INSTANTS];
    for (i, st) in out.iter_mut().enumerate() {
        let (mut sq_pos, mut sq_th, mut nees) = (0.0, 0.0, 0.0);
        let (mut odo_pos, mut odo_th) = (0.0, 0.0);
        let (mut truth, mut est) = ([0.0; 3], [0.0; 3]);
        for run in runs {
            let s = &run[i];
            sq_pos += s.position_error_sq();
            sq_th += s.heading_error * s.heading_error;
            nees += s.nees;
            if let Some((p, th)) = s.odometry {
                odo_pos += (s.truth[0] - p[0]).powi(2) + (s.truth[1] - p[1]).powi(2);
                odo_th += th * th;
            }
            truth[0] += s.truth[0];
            truth[1] += s.truth[1];
            truth[2] += s.truth_heading;
            est[0] += s.estimate[0];
            est[1] += s.estimate[1];
            est[2] += s.truth_heading - s.heading_error;
        }
        *st = InstantStats {
            truth: truth.map(|v| v / n),
            estimate: est.map(|v| v / n),
            position_rmse: (sq_pos / n).sqrt(),
            heading_rmse: (sq_th / n).sqrt(),
            mean_nees: nees / n,
            odometry_position_rmse: (odo_pos / n).sqrt(),
            odometry_heading_rmse: (odo_th / n).sqrt(),
        };
    }
    out
}

/// Table III by Monte Carlo: `cfg` run from every seed of `seeds` with the
/// paper's `H` and with the exact model (in parallel, rayon), calling
/// `progress` once per finished run (two per seed). The other fields of
/// `cfg` (including `model`) are kept; `model` is overridden per column.
///
/// # Errors
/// [`Error::Config`] for an invalid configuration or an empty seed range;
/// the first run error otherwise.
pub fn table3(
    cfg: &Wall45Config,
    seeds: core::ops::Range<u64>,
    progress: &(impl Fn() + Sync),
) -> Result<Table3, Error> {
    use rayon::prelude::*;

    cfg.validate()?;
    if seeds.is_empty() {
        return Err(Error::Config("table3 needs at least one seed"));
    }
    let column = |model: LaserModel| -> Result<Vec<[Sample; INSTANTS]>, Error> {
        let c = Wall45Config { model, ..*cfg };
        seeds
            .clone()
            .into_par_iter()
            .map(|seed| {
                let r = instants_of_run(&c, seed);
                progress();
                r
            })
            .collect()
    };
    let paper = column(LaserModel::Paper)?;
    let exact = column(LaserModel::Exact)?;
    Ok(Table3 {
        runs: paper.len(),
        paper_h: stats(&paper),
        exact: stats(&exact),
    })
}
