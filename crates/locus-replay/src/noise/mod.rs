//! Noise and odometry delay estimated from the log alone (no ground truth).
//!
//! Three estimates, each with a method that works on logs like MRCLAM's:
//!
//! * **Odometry delay** (how long after a commanded velocity the robot moves
//!   as commanded): the delay of a grid ([`DELAYS`]) that minimises the
//!   filter's innovation negative log-likelihood, all else fixed. A robot
//!   that lags its commands makes every prediction late, and the
//!   sightings say so.
//! * **Measurement noise** by expectation-maximisation over the smoother
//!   (Shumway and Stoffer, "An approach to time series smoothing and
//!   forecasting using the EM algorithm", J. Time Series Analysis 3(4),
//!   1982; for the extended smoother, Sarkka, "Bayesian Filtering and
//!   Smoothing", 2013, section 12.2.3): the M-step's variance is the
//!   spread of the sightings' residuals against the smoothed trajectory
//!   plus the smoother's own uncertainty in the predicted measurement
//!   (`H Ps H^T`). Two changes for real logs: the spread is taken robustly
//!   (1.4826 times the median absolute deviation), so the 1-4 % of gross
//!   outliers do not set it; and errors that persist (a camera's range to
//!   a landmark is often wrong the same way for seconds) are accounted for
//!   by their integrated autocorrelation time `tau`, estimated by batch
//!   means (Flyvbjerg and Petersen, "Error estimates on averages of
//!   correlated data", J. Chem. Phys. 91, 1989: residuals grouped by
//!   landmark in windows of [`WINDOW`] seconds, `tau = mean(n_w m_w^2) /
//!   sigma^2`); each sighting then gets the variance `sigma^2 tau`, what a
//!   correlated sequence is worth when it is applied as independent
//!   (inflation for neglected correlation, as in Stewart, Dance and
//!   Nichols, "Correlated observation errors in data assimilation", Int.
//!   J. Numer. Meth. Fluids 56, 2008).
//! * **Process noise**: each of `q_v` and `q_omega` from the drift of dead
//!   reckoning between pose fixes ([`crate::drift`]) where the log tells
//!   it (more than two standard errors above 0); else the factor on it of
//!   a grid ([`Q_FACTORS`], then [`REFINE`] about the best) that minimises
//!   the innovation negative log-likelihood, searched one after the other
//!   twice (coordinate descent), with a standard error from the
//!   likelihood-ratio interval ([`Estimate::q_se`]).
//!
//! * **Covariance matching after the gaps**: the first sighting after a
//!   gap of [`GAP`] s or more is predicted through it, so its NIS says
//!   whether the covariance grew as fast as the error. Errors that persist
//!   for seconds (commanded velocities) grow faster than the white noise
//!   the likelihood fits; the process noise is raised until the median
//!   post-gap NIS is at most chi-square's median.
//!
//! The order: measurement rounds until the noise settles ([`CONVERGED`],
//! at most [`MAX_ROUNDS`]), the delay, the process noise, measurement
//! rounds again, the covariance matching after the gaps. Each round replays the whole log (the smoother's rounds
//! twice as long as the filter's).
//!
//! What this recovers is measured in docs/replay.md and by `locus family`:
//! on simulated robots with white noise it recovers the measurement noise
//! within a few per cent and the process noise where the log tells it; a
//! correlated error or heavy tails widen the measurement noise on purpose,
//! and the level before the widening (`policy::Setting::level`) stays
//! within 10 % of the truth on the family's correlated members;
//! on MRCLAM, whose commanded velocities err the same way for seconds, the
//! gaps' covariance matching raises the process noise 2-8 times.

use alloc::collections::BTreeMap;

use locus_core::nalgebra::{SVector, Vector2};
use locus_core::{MeasurementModel, wrap_angle};
use locus_models::calibrated_range_bearing::CalibratedRangeBearing;
use locus_models::range_bearing::RangeBearing;

use crate::log::NoiseRecords;

mod beams;
mod bias;
mod grid;

pub use bias::{BiasEstimate, LR_HALF, estimate_bias};

use crate::{Config, Error, EventKind, Log, STATE, Step, replay};
use beams::{KeptScan, beam_noise, smoothed_state};
use grid::grid_minimum;

/// Window of the batch-means estimate of the residuals' correlation, s.
pub const WINDOW: f64 = 60.0;
/// The odometry delays tried, s.
pub const DELAYS: [f64; 8] = [0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4];
/// The factors on the process noise tried.
pub const Q_FACTORS: [f64; 11] = [
    0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0,
];

/// The factors tried about the best of [`Q_FACTORS`] (about 3x apart) to
/// refine it.
pub const REFINE: [f64; 5] = [0.5, 0.7, 1.0, 1.4, 2.0];

/// One measurement round's findings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Round {
    /// The settings the round replayed with.
    pub config: Config,
    /// Spread of the range residuals (robust, with the smoother's own
    /// uncertainty), m.
    pub range_spread: f64,
    /// Their integrated autocorrelation time, in sightings (>= 1).
    pub range_tau: f64,
    /// Spread of the bearing residuals, rad.
    pub bearing_spread: f64,
    /// Their integrated autocorrelation time, in sightings (>= 1).
    pub bearing_tau: f64,
    /// Range residuals the round used.
    pub ranges: usize,
    /// Bearing residuals the round used.
    pub bearings: usize,
    /// Spread of the beams' range residuals (robust, with the smoother's
    /// own uncertainty), m; NaN without scans.
    pub beam_spread: f64,
    /// Their integrated autocorrelation time, in scans (>= 1), per beam.
    pub beam_tau: f64,
    /// Beam residuals the round used.
    pub beam_residuals: usize,
    /// The smoother's calibration over the whole log, `(mean, standard
    /// deviation)` in the order of `Report::calibration`.
    pub calibration: [(f64, f64); 4],
}

impl Round {
    /// Standard error of the range noise the round sets, m: the spread's
    /// (1.4826 MAD has 37 % of the efficiency of the standard deviation)
    /// over the effective number of independent residuals `n / tau`.
    #[must_use]
    #[allow(clippy::cast_precision_loss)]
    pub fn range_se(&self) -> f64 {
        spread_se(
            self.range_spread * self.range_tau.sqrt(),
            self.ranges,
            self.range_tau,
        )
    }

    /// Standard error of the bearing noise the round sets, rad.
    #[must_use]
    pub fn bearing_se(&self) -> f64 {
        spread_se(
            self.bearing_spread * self.bearing_tau.sqrt(),
            self.bearings,
            self.bearing_tau,
        )
    }

    /// Standard error of the beams' noise the round sets, m (as
    /// [`Round::range_se`]).
    #[must_use]
    pub fn beam_se(&self) -> f64 {
        spread_se(
            self.beam_spread * self.beam_tau.sqrt(),
            self.beam_residuals,
            self.beam_tau,
        )
    }
}

/// Standard error of a robust spread `sigma` from `n` residuals of
/// autocorrelation time `tau` (NaN with none).
#[allow(clippy::cast_precision_loss)]
fn spread_se(sigma: f64, n: usize, tau: f64) -> f64 {
    let effective = n as f64 / tau.max(1.0);
    if effective < 1.0 {
        return f64::NAN;
    }
    sigma / (2.0 * 0.37 * effective).sqrt()
}

/// The estimate: the settings to replay with, and how they were reached.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The start settings with the estimated `q_v`, `q_omega`,
    /// `sigma_range`, `sigma_bearing` and `odometry_delay`.
    pub config: Config,
    /// The measurement rounds, in order.
    pub rounds: Vec<Round>,
    /// `(delay s, innovation NLL)` for each delay tried.
    pub delays: Vec<(f64, f64)>,
    /// `(factor, innovation NLL)` for each factor tried on `q_v` and on
    /// `q_omega` (empty where the drift gave it).
    pub q_factors: [Vec<(f64, f64)>; 2],
    /// The drift estimate of the process noise.
    pub drift: crate::drift::Drift,
    /// The factor the process noise was raised by after the gaps (1 when
    /// the post-gap sightings found it honest, or were too few).
    pub gap_factor: f64,
}

impl Estimate {
    /// Standard error of `q_v` (`k` = 0, m^2/s) or `q_omega` (`k` = 1,
    /// rad^2/s): the drift's where it gave the value; else from the
    /// likelihood-ratio interval of the factors tried (those whose NLL is
    /// within 1.92 of the smallest: the 95 % interval `[lo, hi]`, at least
    /// as wide as the refined grid's span), as a log-normal's: `q ln(hi /
    /// lo) / 3.92`. Infinite when the interval reaches either end of
    /// [`Q_FACTORS`] (the log cannot tell the value).
    #[must_use]
    pub fn q_se(&self, k: usize) -> f64 {
        let tried = &self.q_factors[k];
        if tried.is_empty() {
            return self.gap_factor
                * if k == 0 {
                    self.drift.q_v_se
                } else {
                    self.drift.q_omega_se
                };
        }
        let q = if k == 0 {
            self.config.q_v
        } else {
            self.config.q_omega
        };
        let best = tried.iter().map(|t| t.1).fold(f64::INFINITY, f64::min);
        let inside: Vec<f64> = tried
            .iter()
            .filter(|t| t.1 <= best + 1.92)
            .map(|t| t.0)
            .collect();
        let lo = inside.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = inside.iter().copied().fold(0.0, f64::max);
        if lo <= Q_FACTORS[0] || hi >= Q_FACTORS[Q_FACTORS.len() - 1] {
            return f64::INFINITY;
        }
        q * (hi / lo).max(REFINE[REFINE.len() - 1] / REFINE[0]).ln() / 3.92
    }
}

/// What a round keeps of each smoothed sighting.
struct Kept {
    time: f64,
    landmark: u32,
    range: f64,
    /// `None` for a range-only sighting: it gives a range residual only.
    bearing: Option<f64>,
    state: SVector<f64, STATE>,
    covariance: locus_core::nalgebra::Matrix3<f64>,
}

/// Robust spread: 1.4826 times the median absolute deviation from the
/// median (NaN if empty).
pub(crate) fn robust_spread(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let median = values[values.len() / 2];
    let mut dev: Vec<f64> = values.iter().map(|v| (v - median).abs()).collect();
    dev.sort_by(f64::total_cmp);
    1.4826 * dev[dev.len() / 2]
}

/// Batch-means integrated autocorrelation time of residuals `(landmark,
/// time, value)` of spread `sigma` (values clipped at 3 sigma so outliers
/// do not set it); at least 1. The window means are compared with the
/// robust `sigma^2`, not the clipped values' own variance: heavy tails
/// then count as correlation and widen the noise, which on MRCLAM's camera
/// is what keeps the filter honest (with the clipped variance robot 4's
/// filter RMSE went 0.21 -> 0.43 m, NEES 18); independent outliers cost a
/// little width (5 % of them: range noise 1.5x the truth).
#[allow(clippy::cast_precision_loss)]
fn batch_tau(residuals: &[(u32, f64, f64)], sigma: f64) -> f64 {
    if sigma.is_nan() || sigma <= 0.0 {
        return 1.0;
    }
    let mut windows: BTreeMap<(u32, i64), (usize, f64)> = BTreeMap::new();
    for &(landmark, t, v) in residuals {
        #[allow(clippy::cast_possible_truncation)]
        let w = (t / WINDOW).floor() as i64;
        let e = windows.entry((landmark, w)).or_insert((0, 0.0));
        e.0 += 1;
        e.1 += v.clamp(-3.0 * sigma, 3.0 * sigma);
    }
    let (mut sum, mut count) = (0.0, 0usize);
    for (n, total) in windows.values() {
        if *n >= 2 {
            let mean = total / *n as f64;
            sum += *n as f64 * mean * mean;
            count += 1;
        }
    }
    if count == 0 {
        return 1.0;
    }
    (sum / count as f64 / (sigma * sigma)).max(1.0)
}

/// One measurement round: replays `log` with `cfg` and the smoother, and
/// sets the measurement noise from the residuals (see the module
/// documentation). Returns the round's findings and the next settings.
///
/// # Errors
/// The replay's errors.
#[allow(clippy::cast_precision_loss)]
pub fn measurement_round(log: &Log, cfg: &Config) -> Result<(Round, Config), Error> {
    let mut kept: Vec<Kept> = Vec::with_capacity(log.sightings.len());
    let mut scans: Vec<KeptScan> = Vec::with_capacity(log.scans.len());
    let run = Config {
        smooth: true,
        evaluate: false,
        ..*cfg
    };
    let report = replay(log, &run, |s: &Step| {
        if let (EventKind::Scan { index, .. }, Some(p), Some(c)) =
            (s.kind, s.smoothed, s.smoothed_calibration)
        {
            scans.push(KeptScan {
                index,
                state: smoothed_state(&p.x, &c),
                covariance: p.p,
            });
        }
        if let (EventKind::Sighting { sighting, .. }, Some(p), Some(c)) =
            (s.kind, s.smoothed, s.smoothed_calibration)
        {
            let state = smoothed_state(&p.x, &c);
            kept.push(Kept {
                time: s.time,
                landmark: sighting.landmark,
                range: sighting.range,
                bearing: sighting.bearing,
                state,
                covariance: p.p,
            });
        }
    })?;
    let mut ranges = Vec::with_capacity(kept.len());
    let mut bearings = Vec::with_capacity(kept.len());
    let mut hph = [0.0, 0.0];
    for k in &kept {
        let Some(l) = log.landmark(k.landmark) else {
            continue;
        };
        let model = CalibratedRangeBearing {
            inner: RangeBearing::new(
                Vector2::new(l.x, l.y),
                Vector2::new(log.sensor.x, log.sensor.y),
                1.0,
                1.0,
            ),
            yaw: log.sensor.yaw,
        };
        let Some(z) = model.h(&k.state) else { continue };
        let h = model
            .jacobian(&k.state)
            .fixed_view::<2, 3>(0, 0)
            .into_owned();
        let s = h * k.covariance * h.transpose();
        hph[0] += s[(0, 0)];
        if k.bearing.is_some() {
            hph[1] += s[(1, 1)];
        }
        ranges.push((k.landmark, k.time, k.range - z[0]));
        if let Some(b) = k.bearing {
            bearings.push((k.landmark, k.time, wrap_angle(b - z[1])));
        }
    }
    let n = ranges.len().max(1) as f64;
    let range_spread =
        robust_spread(ranges.iter().map(|r| r.2).collect()).hypot((hph[0] / n).sqrt());
    let n_bearing = bearings.len().max(1) as f64;
    let bearing_spread =
        robust_spread(bearings.iter().map(|r| r.2).collect()).hypot((hph[1] / n_bearing).sqrt());
    let range_tau = batch_tau(&ranges, range_spread);
    let bearing_tau = batch_tau(&bearings, bearing_spread);
    let (beam_spread, beam_tau, beam_residuals) = beam_noise(log, cfg, &scans);
    let mut next = *cfg;
    let sbeam = beam_spread * beam_tau.sqrt();
    if sbeam.is_finite() && sbeam > 0.0 {
        next.beams.sigma = sbeam;
    }
    let sr = range_spread * range_tau.sqrt();
    let sb = bearing_spread * bearing_tau.sqrt();
    if sr.is_finite() && sr > 0.0 {
        next.sigma_range = sr;
    }
    if sb.is_finite() && sb > 0.0 {
        next.sigma_bearing = sb;
    }
    Ok((
        Round {
            config: *cfg,
            range_spread,
            range_tau,
            bearing_spread,
            bearing_tau,
            ranges: ranges.len(),
            bearings: bearings.len(),
            beam_spread,
            beam_tau,
            beam_residuals,
            calibration: report.smoothed_calibration.unwrap_or(report.calibration),
        },
        next,
    ))
}

/// The innovation negative log-likelihood of a filter-only replay.
fn nll(log: &Log, cfg: &Config) -> Result<f64, Error> {
    let run = Config {
        smooth: false,
        evaluate: false,
        ..*cfg
    };
    Ok(replay(log, &run, |_| {})?.innovation_nll)
}

/// Seconds without a sighting that make the next one a post-gap sighting.
pub const GAP: f64 = 5.0;
/// Post-gap sightings the covariance matching needs.
pub const MIN_POST_GAP: usize = 10;
/// Median of chi-square with 2 dof, `2 ln 2`.
const CHI2_2_MEDIAN: f64 = 1.386_294_361_119_890_6;
/// Factors on the process noise tried, in order, until the post-gap NIS is
/// honest.
pub const GAP_FACTORS: [f64; 9] = [1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0];

/// The median NIS of the first range-bearing sighting after each gap of
/// [`GAP`] s or more, or `None` with fewer than [`MIN_POST_GAP`] of them.
/// (Covariance matching on the innovations, Mehra, "Approaches to adaptive
/// filtering", IEEE Trans. Automatic Control 17(5), 1972, restricted to
/// the sightings whose prediction crossed a gap; the median, so that
/// outliers do not set it.)
fn post_gap_nis(log: &Log, cfg: &Config) -> Result<Option<f64>, Error> {
    let run = Config {
        smooth: false,
        evaluate: false,
        ..*cfg
    };
    let mut last = f64::NEG_INFINITY;
    let mut nis = Vec::new();
    replay(log, &run, |s: &Step| {
        if let EventKind::Sighting {
            sighting, outcome, ..
        } = s.kind
        {
            if sighting.bearing.is_some() && s.time - last >= GAP {
                match outcome {
                    crate::SightingOutcome::Applied { nis: n, .. }
                    | crate::SightingOutcome::Gated { nis: n } => nis.push(n),
                    _ => {}
                }
            }
            last = s.time;
        }
    })?;
    if nis.len() < MIN_POST_GAP {
        return Ok(None);
    }
    nis.sort_by(f64::total_cmp);
    Ok(Some(nis[nis.len() / 2]))
}

/// Most measurement rounds in one run to convergence.
pub const MAX_ROUNDS: usize = 8;
/// Relative change of both measurement noises below which the rounds stop.
pub const CONVERGED: f64 = 0.03;

/// `cfg` with the noise levels `given` put back (they are not estimated).
fn pin(mut cfg: Config, given: &NoiseRecords) -> Config {
    cfg.q_v = given.q_v.unwrap_or(cfg.q_v);
    cfg.q_omega = given.q_omega.unwrap_or(cfg.q_omega);
    cfg.sigma_range = given.sigma_range.unwrap_or(cfg.sigma_range);
    cfg.sigma_bearing = given.sigma_bearing.unwrap_or(cfg.sigma_bearing);
    cfg.beams.sigma = given.sigma_beam.unwrap_or(cfg.beams.sigma);
    cfg
}

/// Measurement rounds from `cfg` until both noises change by less than
/// [`CONVERGED`] (at most [`MAX_ROUNDS`]): expectation-maximisation
/// converges geometrically, slowly from a start far off.
fn converge(
    log: &Log,
    mut cfg: Config,
    given: &NoiseRecords,
    rounds: &mut Vec<Round>,
) -> Result<Config, Error> {
    for _ in 0..MAX_ROUNDS {
        let (r, next) = measurement_round(log, &cfg)?;
        let next = pin(next, given);
        rounds.push(r);
        let change = (next.sigma_range / cfg.sigma_range - 1.0)
            .abs()
            .max((next.sigma_bearing / cfg.sigma_bearing - 1.0).abs())
            .max((next.beams.sigma / cfg.beams.sigma - 1.0).abs());
        cfg = next;
        if change < CONVERGED {
            break;
        }
    }
    Ok(cfg)
}

/// Estimates the noise and the odometry delay of `log`, starting from
/// `start`, keeping the noise levels `given` and, if `delay_given`,
/// `start`'s odometry delay:
///
/// 1. measurement rounds to convergence ([`measurement_round`]);
/// 2. the odometry delay of smallest innovation NLL ([`DELAYS`]);
/// 3. the process noise from the drift of dead reckoning between pose
///    fixes ([`crate::drift::process_noise`]); where the log has too few
///    fixes for it, the factor of [`Q_FACTORS`] of smallest innovation NLL;
/// 4. measurement rounds to convergence again;
/// 5. the process noise raised where the sightings after gaps of [`GAP`] s
///    or more say the covariance grew too slowly through them
///    ([`Estimate::gap_factor`]).
///
/// # Errors
/// The replay's errors.
pub fn estimate(
    log: &Log,
    start: &Config,
    given: &NoiseRecords,
    delay_given: bool,
) -> Result<Estimate, Error> {
    let mut rounds = Vec::new();
    let mut cfg = converge(log, pin(*start, given), given, &mut rounds)?;
    let mut delays = Vec::new();
    if !delay_given {
        let (delay, tried) = estimate_delay(log, &cfg)?;
        cfg.odometry_delay = delay;
        delays = tried;
    }
    let mut q_factors = [Vec::new(), Vec::new()];
    let drift = crate::drift::process_noise(log, &cfg)?;
    // Each process noise from the drift where the log tells it (more than
    // two standard errors above 0); else the factor of `Q_FACTORS` on it
    // of smallest innovation NLL.
    let told = |q: f64, se: f64| q.is_finite() && se.is_finite() && q > 2.0 * se;
    // Coordinate descent, two sweeps: a q_v searched with q_omega at its
    // start would make up for q_omega's error.
    let drifts = [(drift.q_v, drift.q_v_se), (drift.q_omega, drift.q_omega_se)];
    for (k, (q, se)) in [0, 1, 0, 1].map(|k| (k, drifts[k])) {
        let scaled = |c: &Config, f: f64| {
            let mut c = *c;
            if k == 0 {
                c.q_v *= f;
            } else {
                c.q_omega *= f;
            }
            c
        };
        if told(q, se) {
            cfg = if k == 0 {
                Config { q_v: q, ..cfg }
            } else {
                Config { q_omega: q, ..cfg }
            };
            continue;
        }
        let (coarse, mut tried) = grid_minimum(&Q_FACTORS, |f| nll(log, &scaled(&cfg, f)))?;
        let fine = REFINE.map(|r| coarse * r);
        let (factor, more) = grid_minimum(&fine, |f| nll(log, &scaled(&cfg, f)))?;
        tried.extend(more);
        cfg = scaled(&cfg, factor);
        q_factors[k] = tried;
    }
    cfg = pin(cfg, given);
    let mut cfg = converge(log, cfg, given, &mut rounds)?;
    // Covariance matching after the gaps: the likelihood takes the
    // odometry's errors as white, and errors that persist for seconds
    // (commanded velocities a robot follows late or short) grow faster
    // over a long gap than white noise of the same likelihood. The first
    // sighting after a gap is predicted through it, so its NIS says
    // whether the covariance grew as fast as the error: the process noise
    // is raised (never lowered) by the first factor of [`GAP_FACTORS`]
    // whose post-gap NIS has at most chi-square's median.
    let mut gap_factor = 1.0;
    if given.q_v.is_none() && given.q_omega.is_none() {
        for factor in GAP_FACTORS {
            gap_factor = factor;
            let trial = Config {
                q_v: cfg.q_v * factor,
                q_omega: cfg.q_omega * factor,
                ..cfg
            };
            match post_gap_nis(log, &trial)? {
                Some(m) if m > CHI2_2_MEDIAN => {}
                _ => break,
            }
        }
        cfg.q_v *= gap_factor;
        cfg.q_omega *= gap_factor;
    }
    Ok(Estimate {
        gap_factor,
        config: Config {
            smooth: start.smooth,
            evaluate: start.evaluate,
            ..cfg
        },
        rounds,
        delays,
        q_factors,
        drift,
    })
}

/// The odometry delay of `log` alone (the first step of [`estimate`]):
/// the delay of [`DELAYS`] of smallest innovation NLL with `cfg`'s noise.
///
/// # Errors
/// The replay's errors.
pub fn estimate_delay(log: &Log, cfg: &Config) -> Result<(f64, Vec<(f64, f64)>), Error> {
    grid_minimum(&DELAYS, |d| {
        nll(
            log,
            &Config {
                odometry_delay: d,
                ..*cfg
            },
        )
    })
}
