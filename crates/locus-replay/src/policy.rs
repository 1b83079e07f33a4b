//! Which setting wins: the replay's policy for the noise levels and the
//! odometry delay, in one place for every front end (the `locus replay`
//! command, benchmarks, bindings).
//!
//! For each value, in order: the user's explicit choice ([`Overrides`]),
//! then the log's own `noise` record, then what the log itself shows
//! (estimated, [`Estimation`]), then [`Config::default`].
//!
//! With [`Estimation::Noise`] (the command's default) the calibration's
//! two biases are also settled from the log. Each starts free, from 0 with
//! a prior wide enough for a real robot ([`BIAS_PRIOR_STD`], two standard
//! deviations covering a sensor
//! mounted up to 0.1 rad off-axis, a turn rate biased by up to 0.1 rad/s),
//! while the noise is estimated: a bearing offset the filter cannot
//! absorb would otherwise be taken for bearing noise. The smoother over
//! the whole log then says how well the log tells each bias: a bias whose
//! smoothed standard deviation stays above [`HOLD_RATIO`] of its prior is
//! one the log cannot tell (e.g. a bearing offset on a robot that hardly
//! moves); it is held at 0 and reported as held. A bias the log tells is
//! estimated by the replay from its prior, with the uncertainty the filter
//! gives it.
//!
//! For a log with scans, the beams' range bias (a Gauss-Markov state) is
//! given ([`Overrides::beam_bias`]), or searched with the beams' white
//! noise when that noise is estimated ([`crate::noise::estimate_bias`]:
//! maximum likelihood, the nested white model its alternative), else held
//! at 0 ([`RangeBiasSetting`]).

use locus_logs::NoiseRecords;
use locus_models::calibrated_unicycle::GaussMarkov;

use crate::{Config, Error, Log};

/// How much a replay estimates from its log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Estimation {
    /// The odometry delay only (the noise from the flags, the log's records
    /// and the defaults).
    #[default]
    Delay,
    /// The noise and the odometry delay ([`crate::noise::estimate`]).
    Noise,
    /// Nothing: the flags, the log's records and the defaults as they are
    /// (odometry delay 0 unless given).
    Nothing,
}

/// The user's explicit choices; `None` leaves the value to the log.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Overrides {
    /// Noise levels given explicitly (they win over the log's records and
    /// any estimate).
    pub noise: NoiseRecords,
    /// The odometry delay, s.
    pub odometry_delay: Option<f64>,
    /// What to estimate from the log.
    pub estimation: Estimation,
    /// The beams' range bias given explicitly (else searched with the
    /// beams' noise, [`crate::noise::estimate_bias`]).
    pub beam_bias: Option<GaussMarkov<f64>>,
}

/// Where a setting came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// The user's explicit choice.
    Given,
    /// The log's `noise` record.
    LogRecord,
    /// Estimated from the log.
    Estimated,
    /// [`Config::default`].
    Default,
    /// [`Config::default`]: the estimate was asked for, but the log cannot
    /// tell the value (a bearing noise on a log with no bearings).
    Untold,
}

impl core::fmt::Display for Source {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Source::Given => "given",
            Source::LogRecord => "log record",
            Source::Estimated => "estimated from the log",
            Source::Default => "default",
            Source::Untold => "default: the log cannot tell it",
        })
    }
}

/// One setting as settled: its name (with unit), value and source.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setting {
    /// Name as in a `noise` record or `odometry_delay`.
    pub name: &'static str,
    /// Unit of the value.
    pub unit: &'static str,
    /// The value.
    pub value: f64,
    /// Where it came from.
    pub source: Source,
    /// Its standard error when estimated (NaN when the estimate gives
    /// none, or the value was not estimated).
    pub se: f64,
    /// The noise level the log shows, before the replay widens it: a
    /// measurement noise's spread before its correlation widening
    /// (`value / sqrt(tau)`, [`crate::noise`]), a process noise before
    /// the gaps' factor (`value / gap_factor`). Equal to `value` where
    /// nothing was widened or nothing estimated. `value` is what each
    /// sighting or step is given when applied as independent; `level` is
    /// what compares with a sensor's data sheet.
    pub level: f64,
}

/// Prior standard deviations of the turn-rate bias (rad/s) and the
/// bearing bias (rad) when the log settles them.
pub const BIAS_PRIOR_STD: [f64; 2] = [0.05, 0.05];
/// A bias whose smoothed standard deviation over the whole log exceeds
/// this share of its prior is held (the log cannot tell it).
pub const HOLD_RATIO: f64 = 0.5;

/// How a bias of the calibration was settled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasSetting {
    /// `turn-rate bias` or `bearing bias`.
    pub name: &'static str,
    /// Its unit.
    pub unit: &'static str,
    /// Its prior standard deviation while the log was asked.
    pub prior_std: f64,
    /// What the smoother over the whole log found: `(mean, std)`.
    pub smoothed: (f64, f64),
    /// Held at 0 because the log cannot tell it.
    pub held: bool,
}

/// The settled configuration and where each of its noise levels and the
/// odometry delay came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Settled {
    /// The configuration to replay with.
    pub config: Config,
    /// `q_v`, `q_omega`, `sigma_range`, `sigma_bearing`, `odometry_delay`,
    /// in that order.
    pub settings: Vec<Setting>,
    /// The biases, with [`Estimation::Noise`] (else empty: held as the
    /// base configuration says).
    pub biases: Vec<BiasSetting>,
    /// The noise estimate, when one was made.
    pub estimate: Option<crate::noise::Estimate>,
    /// The beams' range bias, for a log with scans.
    pub range_bias: Option<RangeBiasSetting>,
}

/// The beams' range bias a replay settled on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeBiasSetting {
    /// Its process ([`Beams::HELD_BIAS`](crate::Beams::HELD_BIAS) when
    /// held at 0).
    pub bias: GaussMarkov<f64>,
    /// Whether it is held at 0 (the beams' errors white).
    pub held: bool,
    /// Where it came from.
    pub source: Source,
    /// The search, when one ran (whether or not it kept the bias).
    pub search: Option<crate::noise::BiasEstimate>,
}

/// Units of the noise levels, in [`NoiseRecords::NAMES`] order.
const UNITS: [&str; 4] = ["m^2/s", "rad^2/s", "m", "rad"];

fn get(cfg: &Config, name: &str) -> f64 {
    match name {
        "q_v" => cfg.q_v,
        "q_omega" => cfg.q_omega,
        "sigma_range" => cfg.sigma_range,
        _ => cfg.sigma_bearing,
    }
}

fn slot<'a>(cfg: &'a mut Config, name: &str) -> &'a mut f64 {
    match name {
        "q_v" => &mut cfg.q_v,
        "q_omega" => &mut cfg.q_omega,
        "sigma_range" => &mut cfg.sigma_range,
        _ => &mut cfg.sigma_bearing,
    }
}

/// Settles the replay's configuration for `log`: `base` (its other
/// settings: gate, smoother, start...) with each noise level and the
/// odometry delay taken by the policy of the module documentation.
///
/// # Errors
/// An invalid configuration, or the replay's errors while estimating.
pub fn settle(log: &Log, base: &Config, overrides: &Overrides) -> Result<Settled, Error> {
    let defaults = Config::default();
    let mut cfg = *base;
    let mut sources = [Source::Default; 5];
    for (i, name) in NoiseRecords::NAMES.into_iter().enumerate() {
        let (value, source) = match (
            overrides.noise.get(name).flatten(),
            log.noise.get(name).flatten(),
        ) {
            (Some(v), _) => (v, Source::Given),
            (None, Some(v)) => (v, Source::LogRecord),
            (None, None) => (get(&defaults, name), Source::Default),
        };
        *slot(&mut cfg, name) = value;
        sources[i] = source;
    }
    let (beam_sigma, mut beam_source) = match (overrides.noise.sigma_beam, log.noise.sigma_beam) {
        (Some(v), _) => (v, Source::Given),
        (None, Some(v)) => (v, Source::LogRecord),
        (None, None) => (defaults.beams.sigma, Source::Default),
    };
    cfg.beams.sigma = beam_sigma;
    let (mut beam_se, mut beam_widening) = (f64::NAN, 1.0);
    let mut bias_source = Source::Default;
    let mut bias_search = None;
    if let Some(b) = overrides.beam_bias {
        cfg.beams.bias = b;
        bias_source = Source::Given;
    }
    cfg.odometry_delay = overrides.odometry_delay.unwrap_or(0.0);
    sources[4] = if overrides.odometry_delay.is_some() {
        Source::Given
    } else {
        Source::Default
    };
    cfg.validate()?;
    let mut estimate = None;
    let mut errors = [f64::NAN; 5];
    let mut widening = [1.0; 5];
    let mut biases = Vec::new();
    match overrides.estimation {
        Estimation::Nothing => {}
        Estimation::Delay => {
            if overrides.odometry_delay.is_none() {
                let (d, _) = crate::noise::estimate_delay(log, &cfg)?;
                cfg.odometry_delay = d;
                sources[4] = Source::Estimated;
            }
        }
        Estimation::Noise => {
            let mut free = cfg;
            for (k, std) in BIAS_PRIOR_STD.into_iter().enumerate() {
                free.calibration.initial[2 + k] = 0.0;
                free.calibration.std[2 + k] = std;
            }
            let e = crate::noise::estimate(
                log,
                &free,
                &given_or_recorded(&overrides.noise, &log.noise),
                overrides.odometry_delay.is_some(),
            )?;
            cfg = Config {
                calibration: cfg.calibration,
                ..e.config
            };
            let last = e.rounds.last();
            for (i, source) in sources.iter_mut().take(4).enumerate() {
                let untold = match i {
                    2 => last.is_none_or(|r| r.ranges == 0),
                    3 => last.is_none_or(|r| r.bearings == 0),
                    _ => false,
                };
                if *source == Source::Default && untold {
                    *source = Source::Untold;
                    *slot(&mut cfg, NoiseRecords::NAMES[i]) =
                        get(&defaults, NoiseRecords::NAMES[i]);
                } else if *source == Source::Default {
                    *source = Source::Estimated;
                    errors[i] = match i {
                        0 => e.q_se(0),
                        1 => e.q_se(1),
                        2 => e
                            .rounds
                            .last()
                            .map_or(f64::NAN, crate::noise::Round::range_se),
                        _ => e
                            .rounds
                            .last()
                            .map_or(f64::NAN, crate::noise::Round::bearing_se),
                    };
                    widening[i] = match (i, last) {
                        (0 | 1, _) => e.gap_factor,
                        (2, Some(r)) => r.range_tau.sqrt(),
                        (3, Some(r)) => r.bearing_tau.sqrt(),
                        _ => 1.0,
                    };
                }
            }
            if beam_source == Source::Default {
                match last.filter(|r| r.beam_residuals > 0) {
                    Some(r) => {
                        beam_source = Source::Estimated;
                        beam_widening = r.beam_tau.sqrt();
                        beam_se = r.beam_se();
                    }
                    None => {
                        beam_source = Source::Untold;
                        cfg.beams.sigma = defaults.beams.sigma;
                    }
                }
            }
            if overrides.odometry_delay.is_none() {
                sources[4] = Source::Estimated;
            }
            let smoothed = e
                .rounds
                .last()
                .map_or([(f64::NAN, f64::NAN); 4], |r| r.calibration);
            for (k, (name, unit)) in [("turn-rate bias", "rad/s"), ("bearing bias", "rad")]
                .into_iter()
                .enumerate()
            {
                let prior_std = BIAS_PRIOR_STD[k];
                let found = smoothed[2 + k];
                // NaN (no smoother run) holds too.
                let held = found.1.is_nan() || found.1 > HOLD_RATIO * prior_std;
                if !held {
                    cfg.calibration.initial[2 + k] = 0.0;
                    cfg.calibration.std[2 + k] = prior_std;
                }
                biases.push(BiasSetting {
                    name,
                    unit,
                    prior_std,
                    smoothed: found,
                    held,
                });
            }
            estimate = Some(e);
            // The range bias is searched with the beams' white noise it
            // splits, and only where that noise is the log's to tell.
            if beam_source == Source::Estimated && overrides.beam_bias.is_none() {
                let q_v_estimated = sources[0] == Source::Estimated;
                bias_search = crate::noise::estimate_bias(log, &cfg, !q_v_estimated)?;
                if let Some(b) = bias_search {
                    let (sigma, bias, q_v) = b.chosen();
                    cfg.beams.sigma = sigma;
                    cfg.beams.bias = bias;
                    bias_source = Source::Estimated;
                    (beam_se, beam_widening) = (f64::NAN, 1.0);
                    if q_v_estimated {
                        cfg.q_v = q_v;
                        (errors[0], widening[0]) = (f64::NAN, 1.0);
                    }
                }
            }
        }
    }
    let mut settings: Vec<Setting> = NoiseRecords::NAMES
        .into_iter()
        .zip(UNITS)
        .enumerate()
        .map(|(i, (name, unit))| Setting {
            name,
            unit,
            value: get(&cfg, name),
            source: sources[i],
            se: errors[i],
            level: get(&cfg, name) / widening[i],
        })
        .collect();
    if !log.scans.is_empty() {
        settings.push(Setting {
            name: "sigma_beam",
            unit: "m",
            value: cfg.beams.sigma,
            source: beam_source,
            se: beam_se,
            level: cfg.beams.sigma / beam_widening,
        });
    }
    settings.push(Setting {
        name: "odometry_delay",
        unit: "s",
        value: cfg.odometry_delay,
        source: sources[4],
        se: f64::NAN,
        level: cfg.odometry_delay,
    });
    let range_bias = (!log.scans.is_empty()).then(|| RangeBiasSetting {
        bias: cfg.beams.bias,
        held: cfg.beams.bias == crate::Beams::HELD_BIAS,
        source: bias_source,
        search: bias_search,
    });
    Ok(Settled {
        config: cfg,
        settings,
        biases,
        estimate,
        range_bias,
    })
}

/// The noise levels fixed before any estimate: each given one, else each
/// the log records.
fn given_or_recorded(given: &NoiseRecords, recorded: &NoiseRecords) -> NoiseRecords {
    NoiseRecords {
        q_v: given.q_v.or(recorded.q_v),
        q_omega: given.q_omega.or(recorded.q_omega),
        sigma_range: given.sigma_range.or(recorded.sigma_range),
        sigma_bearing: given.sigma_bearing.or(recorded.sigma_bearing),
        sigma_beam: given.sigma_beam.or(recorded.sigma_beam),
    }
}
