//! Settings for a fleet of alike robots: the replay's noise levels and
//! odometry delay tuned on several logs at once, and every log replayed
//! with the built-in and with the tuned values (`locus tune` is its
//! command-line front end; any other front end calls [`tune`] and
//! [`compare`] alike).
//!
//! [`tune`] finds the values by one of four [`Method`]s:
//!
//! * [`Method::Estimate`]: on each log, what [`policy::settle`] estimates
//!   with [`Estimation::Noise`] (the four noise levels and the odometry
//!   delay, as `locus replay` with no flags); each value is the median of
//!   the logs'.
//! * [`Method::Drift`]: on each log, the odometry delay
//!   ([`noise::estimate_delay`]) and then the process noise from the drift
//!   of dead reckoning between pose fixes ([`drift::process_noise`]); each
//!   value the median of the logs'. The measurement noise is the start's.
//! * [`Method::Nll`]: argmin's Nelder-Mead over the four noise levels and
//!   the initial forward-speed and turn-rate scale factors, minimising
//!   [`Report::innovation_nll`] summed over the logs (no ground truth
//!   needed). The odometry delay is the start's.
//! * [`Method::Truth`]: the same search on the summed position RMSE
//!   against the ground truth, m (for comparison only: it needs the truth).
//!
//! The median of an even count is the upper of the two middle values, so
//! that it is always one log's own value.
//!
//! A tuning log with nothing to estimate from (fewer than two odometry
//! records, no landmark sightings), or, for the two median methods, whose
//! estimate fails or comes out non-finite, negative, or zero (a delay of
//! 0 s is valid), is left out of the tuning with its [`Cause`]: one such
//! log would otherwise move every median to another log's value. With no
//! log left, [`tune`] fails with [`TuneError::NoneLeft`].
//!
//! [`compare`] replays every log, tuning logs and held-out ones, with the
//! start and the tuned configuration and reports the [`Figures`] of each;
//! a figure that cannot be computed is `None`, never 0.
//!
//! Units: SI (m, rad, s); noise levels as [`Config`] gives them.

use core::cell::{Cell, RefCell};
use core::fmt;

use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;

use crate::policy::{self, Estimation, Overrides};
use crate::{Config, Error, Log, Report, drift, noise, replay};

/// A log and the name a front end shows for it (a file's path, "robot 3").
pub type NamedLog = (String, Log);

/// How [`tune`] finds the fleet's values (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Method {
    /// The medians of what the replay estimates from each log alone: the
    /// noise levels and the odometry delay.
    Estimate,
    /// The medians of each log's odometry delay and of its process noise
    /// from the drift between pose fixes of the sightings.
    Drift,
    /// Nelder-Mead on the innovations' summed negative log-likelihood.
    Nll,
    /// Nelder-Mead on the summed position RMSE against the ground truth.
    Truth,
}

/// What [`tune`] needs besides the logs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// The method.
    pub method: Method,
    /// The built-in values: the tuned configuration is this one with the
    /// values the method finds, and the Nelder-Mead search starts here.
    pub start: Config,
    /// The replay's other settings (gate, robust weighting, limits...)
    /// under which [`Method::Estimate`] settles each log, as
    /// [`policy::settle`]'s `base`.
    pub base: Config,
    /// Nelder-Mead iterations at most ([`Method::Nll`], [`Method::Truth`]).
    pub max_iters: u64,
}

/// Progress of [`tune`], reported as the work goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Progress {
    /// `done` of the `of` logs estimated (the median methods).
    Estimated {
        /// Logs done so far.
        done: usize,
        /// Logs to do.
        of: usize,
    },
    /// The Nelder-Mead search has evaluated its objective `count` times.
    Evaluated {
        /// Evaluations so far.
        count: u64,
    },
}

/// The result of [`tune`].
#[derive(Debug)]
pub struct Tuned {
    /// [`Options::start`] with the tuned values.
    pub config: Config,
    /// The names of the logs tuned on, in the order given.
    pub tuned_on: Vec<String>,
    /// The logs left out of the tuning and why, in the order found (those
    /// with nothing to estimate from first).
    pub left_out: Vec<LeftOut>,
    /// The Nelder-Mead search, for [`Method::Nll`] and [`Method::Truth`].
    pub search: Option<Search>,
}

impl Tuned {
    /// Whether the log named `name` was left out of the tuning.
    #[must_use]
    pub fn is_left_out(&self, name: &str) -> bool {
        self.left_out.iter().any(|l| l.name == name)
    }
}

/// What the Nelder-Mead search took.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Search {
    /// Iterations.
    pub iterations: u64,
    /// Evaluations of the objective (each a replay of every tuning log).
    pub evaluations: u64,
}

/// A tuning log left out of the tuning.
#[derive(Debug)]
pub struct LeftOut {
    /// Its name.
    pub name: String,
    /// Why.
    pub cause: Cause,
}

/// What was being estimated when an estimate failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Estimated {
    /// The odometry delay ([`noise::estimate_delay`]).
    OdometryDelay,
    /// The process noise ([`drift::process_noise`]).
    ProcessNoise,
    /// The noise and the delay ([`policy::settle`]).
    Noise,
}

impl fmt::Display for Estimated {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Estimated::OdometryDelay => "odometry delay",
            Estimated::ProcessNoise => "process noise",
            Estimated::Noise => "noise",
        })
    }
}

/// Why a tuning log has no estimate. Its `Display` is a sentence for the
/// user, with the whole chain of a failed estimate's error.
#[derive(Debug)]
#[non_exhaustive]
pub enum Cause {
    /// Fewer than two odometry records: no motion to estimate from.
    NoMotion {
        /// The log's odometry records (0 or 1).
        odometry: usize,
    },
    /// No landmark sightings: no innovation to estimate from.
    NoSightings,
    /// The estimate failed.
    Failed {
        /// What was being estimated.
        what: Estimated,
        /// The log's own name ([`Log::name`]).
        log: String,
        /// The replay's error.
        error: Error,
    },
    /// A value came out non-finite, negative or zero (a delay of 0 s is
    /// valid): the log does not tell it.
    NotPositive {
        /// The value's name (`q_v`, `q_omega`, `sigma_range`,
        /// `sigma_bearing`, `odometry delay`).
        value: &'static str,
        /// What it came out.
        got: f64,
    },
}

impl fmt::Display for Cause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Cause::NoMotion { odometry } => write!(
                f,
                "{odometry} odometry record{}: no motion to estimate from (at least 2 needed)",
                if *odometry == 1 { "" } else { "s" }
            ),
            Cause::NoSightings => {
                f.write_str("no landmark sightings: no innovation to estimate from")
            }
            Cause::Failed { what, log, error } => {
                write!(f, "estimating the {what} of {log}: {error}")?;
                let mut source = core::error::Error::source(error);
                while let Some(s) = source {
                    write!(f, ": {s}")?;
                    source = s.source();
                }
                Ok(())
            }
            Cause::NotPositive { value, got } => {
                write!(f, "its {value} came out {got} (the log does not tell it)")
            }
        }
    }
}

/// Errors of [`tune`] and [`compare`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TuneError {
    /// Every tuning log was left out (or none was given).
    #[error(
        "no tuning log has an estimate, nothing to tune on: {}",
        list(left_out)
    )]
    NoneLeft {
        /// Each log and its cause.
        left_out: Vec<LeftOut>,
    },
    /// A replay failed (in the search's objective or in [`compare`]).
    #[error("replaying {log}")]
    Replay {
        /// The log's name.
        log: String,
        /// The replay's error.
        #[source]
        error: Error,
    },
    /// The Nelder-Mead search failed (argmin's message).
    #[error("Nelder-Mead: {0}")]
    Search(String),
}

fn list(left_out: &[LeftOut]) -> String {
    let each: Vec<String> = left_out
        .iter()
        .map(|l| format!("{}: {}", l.name, l.cause))
        .collect();
    each.join("; ")
}

/// Tunes the fleet's values on `logs` by `options.method` (module
/// documentation), reporting its progress to `progress`.
///
/// # Errors
/// [`TuneError::NoneLeft`] when no log is left to tune on;
/// [`TuneError::Replay`] when a replay of the search fails;
/// [`TuneError::Search`] when the search itself fails.
pub fn tune(
    logs: &[NamedLog],
    options: &Options,
    mut progress: impl FnMut(Progress),
) -> Result<Tuned, TuneError> {
    let start = &options.start;
    // Logs with nothing to estimate from are left out before any work.
    let mut left_out = Vec::new();
    let mut usable = Vec::with_capacity(logs.len());
    for (name, log) in logs {
        match no_basis(log) {
            Some(cause) => left_out.push(LeftOut {
                name: name.clone(),
                cause,
            }),
            None => usable.push((name, log)),
        }
    }
    let (config, search) = match options.method {
        Method::Drift => {
            let each = each_log(
                &usable,
                |log| {
                    let failed = |what| {
                        move |error| Cause::Failed {
                            what,
                            log: log.name.clone(),
                            error,
                        }
                    };
                    let (delay, _) = noise::estimate_delay(log, start)
                        .map_err(failed(Estimated::OdometryDelay))?;
                    let cfg = Config {
                        odometry_delay: delay,
                        ..*start
                    };
                    let d =
                        drift::process_noise(log, &cfg).map_err(failed(Estimated::ProcessNoise))?;
                    Ok((d.q_v, d.q_omega, delay))
                },
                |e| vec![("q_v", e.0), ("q_omega", e.1), ("odometry delay", e.2)],
                &mut left_out,
                &mut progress,
            )?;
            let config = Config {
                q_v: median(each.iter().map(|e| e.0).collect()),
                q_omega: median(each.iter().map(|e| e.1).collect()),
                odometry_delay: median(each.iter().map(|e| e.2).collect()),
                ..*start
            };
            (config, None)
        }
        Method::Estimate => {
            let overrides = Overrides {
                estimation: Estimation::Noise,
                ..Overrides::default()
            };
            let each = each_log(
                &usable,
                |log| {
                    Ok(policy::settle(log, &options.base, &overrides)
                        .map_err(|error| Cause::Failed {
                            what: Estimated::Noise,
                            log: log.name.clone(),
                            error,
                        })?
                        .config)
                },
                |c| {
                    vec![
                        ("q_v", c.q_v),
                        ("q_omega", c.q_omega),
                        ("sigma_range", c.sigma_range),
                        ("sigma_bearing", c.sigma_bearing),
                        ("odometry delay", c.odometry_delay),
                    ]
                },
                &mut left_out,
                &mut progress,
            )?;
            let pick = |f: fn(&Config) -> f64| median(each.iter().map(f).collect());
            let config = Config {
                q_v: pick(|c| c.q_v),
                q_omega: pick(|c| c.q_omega),
                sigma_range: pick(|c| c.sigma_range),
                sigma_bearing: pick(|c| c.sigma_bearing),
                odometry_delay: pick(|c| c.odometry_delay),
                ..*start
            };
            (config, None)
        }
        Method::Nll | Method::Truth => {
            if usable.is_empty() {
                return Err(TuneError::NoneLeft { left_out });
            }
            let score = if options.method == Method::Truth {
                Score::Truth
            } else {
                Score::Nll
            };
            let (config, search) =
                nelder_mead(&usable, start, score, options.max_iters, &mut progress)?;
            (config, Some(search))
        }
    };
    let tuned_on = logs
        .iter()
        .map(|(n, _)| n)
        .filter(|n| !left_out.iter().any(|l| &l.name == *n))
        .cloned()
        .collect();
    Ok(Tuned {
        config,
        tuned_on,
        left_out,
        search,
    })
}

/// Why `log` has nothing to estimate from, if so: fewer than two odometry
/// records (no motion) or no landmark sightings (no innovation).
fn no_basis(log: &Log) -> Option<Cause> {
    let odometry = log.odometry.len();
    if odometry < 2 {
        Some(Cause::NoMotion { odometry })
    } else if log.sightings.is_empty() {
        Some(Cause::NoSightings)
    } else {
        None
    }
}

/// `estimate` on each of `logs`, in order; the estimates of the logs where
/// it succeeds and every named value (`values`) is finite and `> 0`
/// (`>= 0` for the odometry delay), the others added to `left_out` with the
/// cause. Fails when no log is left.
fn each_log<T>(
    logs: &[(&String, &Log)],
    estimate: impl Fn(&Log) -> Result<T, Cause>,
    values: impl Fn(&T) -> Vec<(&'static str, f64)>,
    left_out: &mut Vec<LeftOut>,
    progress: &mut impl FnMut(Progress),
) -> Result<Vec<T>, TuneError> {
    let mut each = Vec::with_capacity(logs.len());
    for (done, (name, log)) in logs.iter().enumerate() {
        let cause = match estimate(log) {
            Ok(e) => {
                let bad = values(&e).into_iter().find(|&(k, v)| {
                    !v.is_finite() || v < 0.0 || (v == 0.0 && k != "odometry delay")
                });
                match bad {
                    None => {
                        each.push(e);
                        None
                    }
                    Some((value, got)) => Some(Cause::NotPositive { value, got }),
                }
            }
            Err(cause) => Some(cause),
        };
        if let Some(cause) = cause {
            left_out.push(LeftOut {
                name: (*name).clone(),
                cause,
            });
        }
        progress(Progress::Estimated {
            done: done + 1,
            of: logs.len(),
        });
    }
    if each.is_empty() {
        return Err(TuneError::NoneLeft {
            left_out: core::mem::take(left_out),
        });
    }
    Ok(each)
}

/// The median of `values` (the upper one of an even count; NaN if empty).
fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

/// What the Nelder-Mead search minimises, summed over the tuning logs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Score {
    /// [`Report::innovation_nll`].
    Nll,
    /// The filter's position RMSE against the ground truth, m.
    Truth,
}

/// The parameters searched: `[ln q_v, ln q_omega, ln sigma_range,
/// ln sigma_bearing, v_scale, omega_scale]` (logarithms keep the noise
/// levels positive).
fn to_params(c: &Config) -> Vec<f64> {
    vec![
        c.q_v.ln(),
        c.q_omega.ln(),
        c.sigma_range.ln(),
        c.sigma_bearing.ln(),
        c.calibration.initial[0],
        c.calibration.initial[1],
    ]
}

/// `start` with the parameters `p` of [`to_params`].
fn from_params(p: &[f64], start: &Config) -> Config {
    let mut c = Config {
        q_v: p[0].exp(),
        q_omega: p[1].exp(),
        sigma_range: p[2].exp(),
        sigma_bearing: p[3].exp(),
        ..*start
    };
    c.calibration.initial[0] = p[4];
    c.calibration.initial[1] = p[5];
    c
}

/// The optimiser's problem: the [`Score`] summed over the tuning logs.
struct Problem<'a, P: FnMut(Progress)> {
    logs: &'a [(&'a String, &'a Log)],
    start: &'a Config,
    score: Score,
    evaluations: &'a Cell<u64>,
    progress: RefCell<&'a mut P>,
}

impl<P: FnMut(Progress)> CostFunction for Problem<'_, P> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, p: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        let count = self.evaluations.get() + 1;
        self.evaluations.set(count);
        (self.progress.borrow_mut())(Progress::Evaluated { count });
        let cfg = from_params(p, self.start);
        if cfg.validate().is_err() {
            // Outside the valid domain (a scale <= 0, an overflow): worse
            // than any valid point.
            return Ok(f64::MAX);
        }
        let mut sum = 0.0;
        for (name, log) in self.logs {
            let r = replay(log, &cfg, |_| {}).map_err(|error| TuneError::Replay {
                log: (*name).clone(),
                error,
            })?;
            sum += match self.score {
                Score::Nll => r.innovation_nll,
                Score::Truth => r.summary.position_rmse,
            };
        }
        Ok(if sum.is_finite() { sum } else { f64::MAX })
    }
}

/// Nelder-Mead on `score` over the noise levels and the initial scale
/// factors, from `start`.
fn nelder_mead(
    logs: &[(&String, &Log)],
    start: &Config,
    score: Score,
    max_iters: u64,
    progress: &mut impl FnMut(Progress),
) -> Result<(Config, Search), TuneError> {
    let p0 = to_params(start);
    // Initial simplex: the start and one vertex per parameter, each moved
    // by a factor e^0.5 (noise levels) or by 0.05 (scale factors).
    let mut simplex = vec![p0.clone()];
    for i in 0..p0.len() {
        let mut v = p0.clone();
        v[i] += if i < 4 { 0.5 } else { 0.05 };
        simplex.push(v);
    }
    let search_error = |e: argmin::core::Error| match e.downcast::<TuneError>() {
        Ok(t) => t,
        Err(e) => TuneError::Search(e.to_string()),
    };
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(1e-3)
        .map_err(search_error)?;
    let evaluations = Cell::new(0);
    let problem = Problem {
        logs,
        start,
        score,
        evaluations: &evaluations,
        progress: RefCell::new(progress),
    };
    let result = Executor::new(problem, solver)
        .configure(|s| s.max_iters(max_iters))
        .run()
        .map_err(search_error)?;
    let state = result.state();
    let best = state
        .get_best_param()
        .ok_or_else(|| TuneError::Search("no parameters returned".to_string()))?;
    Ok((
        from_params(best, start),
        Search {
            iterations: state.get_iter(),
            evaluations: evaluations.get(),
        },
    ))
}

/// A log's role in the tuning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Role {
    /// Tuned on.
    TunedOn,
    /// Given to tune on, but left out ([`Tuned::left_out`]).
    LeftOut,
    /// Held out: only replayed.
    HeldOut,
}

/// A replay's figures for [`compare`]; `None` where one cannot be
/// computed or is not finite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Figures {
    /// The filter's position RMSE against the ground truth, m (`None`
    /// unless at least two odometry records were replayed and two events
    /// compared with the truth).
    pub position_rmse_m: Option<f64>,
    /// The filter's heading RMSE, rad (as `position_rmse_m`).
    pub heading_rmse_rad: Option<f64>,
    /// Dead reckoning's position RMSE, m (as `position_rmse_m`).
    pub odometry_position_rmse_m: Option<f64>,
    /// Share of the sightings judged that the gate rejected, in [0, 1]
    /// (`None` if no sighting was judged).
    pub gated_share: Option<f64>,
    /// The smallest of the x, y and heading shares of compared events
    /// inside the filter's 3 sigma, in [0, 1] (as `position_rmse_m`).
    pub worst_within_3_sigma: Option<f64>,
    /// [`Report::innovation_nll`] (as `gated_share`).
    pub innovation_nll: Option<f64>,
}

impl Figures {
    /// The figures of `r`.
    #[must_use]
    pub fn of(r: &Report) -> Self {
        let moved = r.odometry >= 2 && r.compared >= 2;
        let judged = r.applied + r.gated > 0;
        let keep = |ok: bool, v: f64| Some(v).filter(|v| ok && v.is_finite());
        let worst = r
            .summary
            .within_3_sigma
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        Figures {
            position_rmse_m: keep(moved, r.summary.position_rmse),
            heading_rmse_rad: keep(moved, r.summary.heading_rmse),
            odometry_position_rmse_m: keep(moved, r.summary.odometry_position_rmse),
            gated_share: keep(judged, r.gated_share()),
            worst_within_3_sigma: keep(moved, worst),
            innovation_nll: keep(judged, r.innovation_nll),
        }
    }
}

/// One log replayed with the start and with the tuned values.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// The log's name.
    pub name: String,
    /// Its role.
    pub role: Role,
    /// With [`Options::start`].
    pub built_in: Figures,
    /// With [`Tuned::config`].
    pub tuned: Figures,
}

/// Replays each of `tuning` (the logs given to [`tune`]) and `held_out`
/// with `start` and with `tuned.config`, in that order.
///
/// # Errors
/// [`TuneError::Replay`] naming the log whose replay failed.
pub fn compare(
    tuning: &[NamedLog],
    held_out: &[NamedLog],
    tuned: &Tuned,
    start: &Config,
) -> Result<Vec<Comparison>, TuneError> {
    let role = |name: &str| {
        if tuned.is_left_out(name) {
            Role::LeftOut
        } else {
            Role::TunedOn
        }
    };
    tuning
        .iter()
        .map(|(n, l)| (n, role(n), l))
        .chain(held_out.iter().map(|(n, l)| (n, Role::HeldOut, l)))
        .map(|(name, role, log)| {
            let run = |cfg: &Config| {
                replay(log, cfg, |_| {})
                    .map(|r| Figures::of(&r))
                    .map_err(|error| TuneError::Replay {
                        log: name.clone(),
                        error,
                    })
            };
            Ok(Comparison {
                name: name.clone(),
                role,
                built_in: run(start)?,
                tuned: run(&tuned.config)?,
            })
        })
        .collect()
}
