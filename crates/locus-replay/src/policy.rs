//! Which setting wins: the replay's policy for the noise levels and the
//! odometry delay, in one place for every front end (the `locus replay`
//! command, benchmarks, bindings).
//!
//! For each value, in order: the user's explicit choice ([`Overrides`]),
//! then the log's own `noise` record, then what the log itself shows
//! (estimated, [`Estimation`]), then [`Config::default`].

use locus_logs::NoiseRecords;

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
}

impl core::fmt::Display for Source {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Source::Given => "given",
            Source::LogRecord => "log record",
            Source::Estimated => "estimated from the log",
            Source::Default => "default",
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
    /// The noise estimate, when one was made.
    pub estimate: Option<crate::noise::Estimate>,
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
    cfg.odometry_delay = overrides.odometry_delay.unwrap_or(0.0);
    sources[4] = if overrides.odometry_delay.is_some() {
        Source::Given
    } else {
        Source::Default
    };
    cfg.validate()?;
    let mut estimate = None;
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
            let e = crate::noise::estimate(log, &cfg)?;
            for (i, name) in NoiseRecords::NAMES.into_iter().enumerate() {
                if matches!(sources[i], Source::Given | Source::LogRecord) {
                    continue;
                }
                *slot(&mut cfg, name) = get(&e.config, name);
                sources[i] = Source::Estimated;
            }
            if overrides.odometry_delay.is_none() {
                cfg.odometry_delay = e.config.odometry_delay;
                sources[4] = Source::Estimated;
            }
            estimate = Some(e);
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
        })
        .collect();
    settings.push(Setting {
        name: "odometry_delay",
        unit: "s",
        value: cfg.odometry_delay,
        source: sources[4],
    });
    Ok(Settled {
        config: cfg,
        settings,
        estimate,
    })
}
