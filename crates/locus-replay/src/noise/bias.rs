//! The beams' range bias from the log: the part of a range sensor's error
//! that persists from scan to scan, as the Gauss-Markov state of
//! [`CalibratedUnicycle`](locus_models::calibrated_unicycle::CalibratedUnicycle).
//!
//! Why a state and not a wider white noise: a range error that persists
//! for seconds, taken as white, is averaged over many scans as if it were
//! independent, and the filter becomes sure of a position the error has
//! moved. The expectation-maximisation rounds cannot see it either: the
//! smoother follows the slow part of the error as if it were motion, so
//! the residuals it leaves are small and white.
//!
//! The maximum-likelihood estimate does separate the two: the odometry's
//! random walk grows without bound, a Gauss-Markov error does not. Four
//! values are searched at once, by argmin's Nelder-Mead on their
//! logarithms, minimising the filter's innovation negative
//! log-likelihood ([`Report::innovation_nll`](crate::Report)): the beams'
//! white noise `sigma_beam`, the bias's stationary standard deviation and
//! time constant, and `q_v` (the process noise the bias trades against)
//! unless it was given. The same search with the bias held (`sigma_beam`
//! and `q_v` alone) is the nested white model; the estimate is whichever
//! of the two has the smaller NLL ([`BiasEstimate::chosen`]): on white
//! beams the search finds a bias too small to matter, or none better. By
//! how much the bias explains the log better is reported: a likelihood
//! ratio beyond chi-square's 99 % point with 2 degrees of freedom
//! ([`LR_HALF`]) is [`BiasEstimate::significant`]. That test is not a
//! gate: a bias kept in vain costs a little uncertainty, a bias dropped
//! in vain makes the filter over-confident, and on a log like
//! laser_wall_1d the odometry's walk explains most of what a persistent
//! range error does, so the likelihood favours the bias by little even
//! where it is real.

use core::cell::{Cell, RefCell};

use alloc::vec;
use alloc::vec::Vec;

use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use locus_models::calibrated_unicycle::GaussMarkov;

use super::nll;
use crate::{Beams, Config, Error, Log};

/// Half chi-square's 99 % point with 2 degrees of freedom (`ln 100`): the
/// fall in the innovation NLL beyond which the bias's two values are
/// significant.
pub const LR_HALF: f64 = 4.605_170_185_988_091;

/// Nelder-Mead iterations at most, per simplex search.
pub const MAX_ITERATIONS: u64 = 100;

/// The search's start for the time constant, in median intervals between
/// scans.
const TAU_START_SCANS: f64 = 10.0;

/// What the search found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasEstimate {
    /// The beams' white noise, m.
    pub sigma_beam: f64,
    /// The range bias (m, s).
    pub bias: GaussMarkov<f64>,
    /// The forward-speed process noise searched beside them, m^2/s (the
    /// start's where it was given).
    pub q_v: f64,
    /// The filter's innovation NLL at the found values.
    pub nll: f64,
    /// The same with the bias held at 0 and `sigma_beam` and `q_v`
    /// searched alike.
    pub white_nll: f64,
    /// The white noise that search found, m.
    pub white_sigma_beam: f64,
    /// The `q_v` it found, m^2/s.
    pub white_q_v: f64,
    /// Replays the search ran.
    pub evaluations: u64,
}

impl BiasEstimate {
    /// Whether the bias explains the log better than white noise by the
    /// likelihood ratio of [`LR_HALF`].
    #[must_use]
    pub fn significant(&self) -> bool {
        self.white_nll - self.nll > LR_HALF
    }

    /// The maximum-likelihood choice: `(sigma_beam, bias, q_v)` of the
    /// search with the bias where its NLL is the smaller, else of the
    /// white search with the bias held.
    #[must_use]
    pub fn chosen(&self) -> (f64, GaussMarkov<f64>, f64) {
        if self.nll < self.white_nll {
            (self.sigma_beam, self.bias, self.q_v)
        } else {
            (self.white_sigma_beam, Beams::HELD_BIAS, self.white_q_v)
        }
    }
}

/// What a search varies.
#[derive(Clone, Copy)]
struct Space {
    /// The bias's `sigma` and `tau` (else held).
    bias: bool,
    /// `q_v` (else the start's).
    q_v: bool,
}

impl Space {
    /// The logarithms of `sigma_beam`, then (if searched) of the bias's
    /// `sigma` and `tau`, then of `q_v`.
    fn params(self, c: &Config) -> Vec<f64> {
        let mut p = vec![c.beams.sigma.ln()];
        if self.bias {
            p.extend([c.beams.bias.sigma.ln(), c.beams.bias.tau.ln()]);
        }
        if self.q_v {
            p.push(c.q_v.ln());
        }
        p
    }

    fn config(self, start: &Config, p: &[f64]) -> Config {
        let mut c = *start;
        c.beams.sigma = p[0].exp();
        let mut rest = p[1..].iter();
        if self.bias
            && let (Some(s), Some(t)) = (rest.next(), rest.next())
        {
            c.beams.bias = GaussMarkov {
                sigma: s.exp(),
                tau: t.exp(),
            };
        }
        if self.q_v
            && let Some(q) = rest.next()
        {
            c.q_v = q.exp();
        }
        c
    }
}

struct Problem<'a> {
    log: &'a Log,
    start: &'a Config,
    space: Space,
    evaluations: &'a Cell<u64>,
    failure: &'a RefCell<Option<Error>>,
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, p: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        self.evaluations.set(self.evaluations.get() + 1);
        let cfg = self.space.config(self.start, p);
        if cfg.validate().is_err() {
            return Ok(f64::MAX);
        }
        match nll(self.log, &cfg) {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Ok(f64::MAX),
            Err(e) => {
                self.failure.replace(Some(e));
                Err(argmin::core::Error::msg("the replay failed"))
            }
        }
    }
}

/// Searches `log`'s range bias from `start` (its white `sigma_beam` and
/// `q_v` the search's start; `q_v` kept if `q_v_given`). `None` for a log
/// without scans or a map.
///
/// # Errors
/// The replay's errors.
pub fn estimate_bias(
    log: &Log,
    start: &Config,
    q_v_given: bool,
) -> Result<Option<BiasEstimate>, Error> {
    if log.scans.len() < 2 || log.map.is_none() {
        return Ok(None);
    }
    let white = Config {
        beams: Beams {
            bias: Beams::HELD_BIAS,
            ..start.beams
        },
        ..*start
    };
    let mut gaps: Vec<f64> = log
        .scans
        .times()
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    if gaps.is_empty() {
        return Ok(None);
    }
    gaps.sort_by(f64::total_cmp);
    let gap = gaps[gaps.len() / 2];
    let evaluations = Cell::new(0);
    let (null, white_nll) = search(
        log,
        &white,
        Space {
            bias: false,
            q_v: !q_v_given,
        },
        &evaluations,
    )?;
    let start = Config {
        beams: Beams {
            bias: GaussMarkov {
                sigma: 3.0 * null.beams.sigma,
                tau: TAU_START_SCANS * gap,
            },
            ..null.beams
        },
        ..null
    };
    let (found, nll) = search(
        log,
        &start,
        Space {
            bias: true,
            q_v: !q_v_given,
        },
        &evaluations,
    )?;
    Ok(Some(BiasEstimate {
        sigma_beam: found.beams.sigma,
        bias: found.beams.bias,
        q_v: found.q_v,
        nll,
        white_nll,
        white_sigma_beam: null.beams.sigma,
        white_q_v: null.q_v,
        evaluations: evaluations.get(),
    }))
}

/// Nelder-Mead over `space` from `start`, restarted from its best until a
/// restart gains less than [`RESTART_GAIN`] (at most [`RESTARTS`] times):
/// on a flat likelihood a simplex shrinks before it reaches the minimum
/// (Nelder-Mead's known premature convergence; a restart with a fresh
/// simplex is the usual remedy). The best configuration and its
/// innovation NLL.
fn search(
    log: &Log,
    start: &Config,
    space: Space,
    evaluations: &Cell<u64>,
) -> Result<(Config, f64), Error> {
    let (mut best, mut cost) = simplex_search(log, start, space, evaluations)?;
    for _ in 0..RESTARTS {
        let (next, c) = simplex_search(log, &best, space, evaluations)?;
        let gain = cost - c;
        if c < cost {
            (best, cost) = (next, c);
        }
        if gain < RESTART_GAIN {
            break;
        }
    }
    Ok((best, cost))
}

/// Restarts of the search at most.
pub const RESTARTS: usize = 2;
/// The fall in the innovation NLL below which a restart ends the search.
pub const RESTART_GAIN: f64 = 0.1;

/// One Nelder-Mead search over `space` from `start`.
fn simplex_search(
    log: &Log,
    start: &Config,
    space: Space,
    evaluations: &Cell<u64>,
) -> Result<(Config, f64), Error> {
    let p0 = space.params(start);
    // Steps of e^1.5 (a factor 4.5): the likelihood is flat along the
    // ridge where the bias trades against the odometry's walk, and a
    // small simplex stops on it.
    let mut simplex = vec![p0.clone()];
    for i in 0..p0.len() {
        let mut v = p0.clone();
        v[i] += 1.5;
        simplex.push(v);
    }
    let failure = RefCell::new(None);
    let problem = Problem {
        log,
        start,
        space,
        evaluations,
        failure: &failure,
    };
    // Converged when the simplex's NLL values spread by less than 0.01:
    // differences that small do not move the estimate's honesty.
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(0.01)
        .map_err(|_| Error::InvalidConfig("range bias search"))?;
    let result = Executor::new(problem, solver)
        .configure(|s| s.max_iters(MAX_ITERATIONS))
        .run();
    if let Some(e) = failure.borrow_mut().take() {
        return Err(e);
    }
    let result = result.map_err(|_| Error::InvalidConfig("range bias search"))?;
    let state = result.state();
    let best = state
        .get_best_param()
        .ok_or(Error::InvalidConfig("range bias search"))?;
    Ok((space.config(start, best), state.get_best_cost()))
}
