//! `locus.replay`: a recorded log (a file, or numpy arrays) through the
//! same engine and defaults as `locus replay` ([`locus_replay::prepare`],
//! [`locus_replay::replay_until`]), the steps returned as arrays.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use locus_eval::results::{Metrics, Results, Source};
use locus_logs::locus_csv::{LandmarkMeasurement, LocusLog, MapLandmark};
use locus_logs::mrclam::{Dataset, Groundtruth, Odometry, TruthPose};
use locus_replay::policy::Estimation;
use locus_replay::results::Section;
use locus_replay::{EventKind, GaussMarkov, Log, Options, SightingOutcome, Step};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyDictMethods};

use crate::arrays;
use crate::error::{locus_error, value_error};
use crate::interrupt::{self, Stop};

/// A log's format, as `locus replay` names its sources.
#[derive(Clone, Copy)]
enum Format {
    Mrclam,
    Csv,
    Librsf,
    Bag,
    Carmen,
    LaserWall,
}

impl Format {
    /// The format `name` names, or the one `path` looks like: a directory
    /// is MRCLAM, `.mcap` a bag, `.log` or `.log.gz` CARMEN, `.txt`
    /// libRSF, anything else Locus CSV. A laser-wall log (`.txt` too) is
    /// only named.
    fn of(name: Option<&str>, path: &Path) -> PyResult<Self> {
        Ok(match name {
            Some("mrclam") => Self::Mrclam,
            Some("csv") => Self::Csv,
            Some("librsf") => Self::Librsf,
            Some("bag") => Self::Bag,
            Some("carmen") => Self::Carmen,
            Some("laser-wall") => Self::LaserWall,
            Some(other) => {
                return Err(value_error(
                    "format",
                    format!(
                        "{other:?} is not one of \"mrclam\", \"csv\", \"librsf\", \"bag\", \"carmen\", \"laser-wall\""
                    ),
                ));
            }
            None if path.is_dir() => Self::Mrclam,
            None if path
                .to_str()
                .is_some_and(|p| p.ends_with(".log") || p.ends_with(".log.gz")) =>
            {
                Self::Carmen
            }
            None => match path.extension().and_then(|e| e.to_str()) {
                Some("mcap") => Self::Bag,
                Some("txt") => Self::Librsf,
                _ => Self::Csv,
            },
        })
    }
}

/// Where a log's companions are: a bag's mapping, a libRSF log's truth, a
/// CARMEN log's map.
struct Companions {
    topics: Option<PathBuf>,
    truth: Option<PathBuf>,
    map: Option<PathBuf>,
}

/// The log at `path` in `format`.
fn read(path: &Path, format: Format, robot: u32, with: &Companions) -> anyhow::Result<Log> {
    let name = || {
        path.file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    };
    Ok(match format {
        Format::Mrclam => Log::mrclam(&Dataset::open(path)?, robot)?,
        Format::Csv => Log::locus_csv(path)?,
        Format::Librsf => {
            let truth = with
                .truth
                .clone()
                .or_else(|| locus_logs::librsf::sibling_truth(path));
            Log::librsf(path, truth.as_deref())?
        }
        Format::Bag => Log::bag(
            path,
            with.topics
                .as_deref()
                .context("topics=MAPPING.toml is needed to replay a bag")?,
        )?,
        Format::Carmen => {
            let map = with
                .map
                .as_deref()
                .context("map=MAP (a ROS YAML or walls) is needed to replay a CARMEN log")?;
            let mut log = Log::from_locus(&name(), locus_logs::carmen::read(path)?.log)?;
            log.load_map(map)?;
            log
        }
        Format::LaserWall => Log::from_locus(&name(), locus_logs::aer1513::read(path)?.log)?,
    })
}

/// The options a keyword names, each checked as the command line checks
/// its flag.
fn options(overrides: Option<&Bound<'_, PyDict>>) -> PyResult<Options> {
    let mut o = Options::default();
    let Some(overrides) = overrides else {
        return Ok(o);
    };
    let mut bias = [None, None];
    for (key, value) in overrides.iter() {
        let key: String = key.extract()?;
        let name = key.as_str();
        let positive = |v: &Bound<'_, PyAny>| -> PyResult<f64> {
            let x: f64 = v
                .extract()
                .map_err(|_| value_error(name, "expected a number"))?;
            if x.is_finite() && x > 0.0 {
                Ok(x)
            } else {
                Err(value_error(name, format!("{x} is not a finite number > 0")))
            }
        };
        let finite = |v: &Bound<'_, PyAny>| -> PyResult<f64> {
            let x: f64 = v
                .extract()
                .map_err(|_| value_error(name, "expected a number"))?;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(value_error(name, format!("{x} is not finite")))
            }
        };
        let flag = |v: &Bound<'_, PyAny>| -> PyResult<bool> {
            v.extract()
                .map_err(|_| value_error(name, "expected True or False"))
        };
        let optional = |v: &Bound<'_, PyAny>| -> PyResult<Option<f64>> {
            if v.is_none() {
                Ok(None)
            } else {
                positive(v).map(Some)
            }
        };
        match name {
            "gate" => {
                o.gate = optional(&value)?;
                if let Some(g) = o.gate
                    && g >= 1.0
                {
                    return Err(value_error(name, format!("{g} is not in (0, 1)")));
                }
            }
            "robust_dof" => o.robust_dof = optional(&value)?,
            "smooth" => o.smooth = flag(&value)?,
            "start_from_sightings" => o.start_from_sightings = flag(&value)?,
            "v_scale" => o.v_scale = positive(&value)?,
            "omega_scale" => o.omega_scale = positive(&value)?,
            "hold_calibration" => o.hold_calibration = flag(&value)?,
            "initial_std" => {
                let s = arrays::fixed::<3>(name, &value)?;
                if s.iter().any(|v| *v <= 0.0) {
                    return Err(value_error(name, "each standard deviation must be > 0"));
                }
                o.initial_std = Some(s);
            }
            "start" => o.start = Some(arrays::fixed::<3>(name, &value)?),
            "beams_per_scan" => {
                let n: u32 = value
                    .extract()
                    .map_err(|_| value_error(name, "expected a whole number >= 1"))?;
                if n == 0 {
                    return Err(value_error(name, "expected a whole number >= 1"));
                }
                o.beams_per_scan = n;
            }
            "max_speed" => o.limits.max_speed = positive(&value)?,
            "max_turn_rate" => o.limits.max_turn_rate = positive(&value)?,
            "max_odometry_gap" => o.limits.max_odometry_gap = positive(&value)?,
            "q_v" => o.noise.q_v = optional(&value)?,
            "q_omega" => o.noise.q_omega = optional(&value)?,
            "sigma_range" => o.noise.sigma_range = optional(&value)?,
            "sigma_bearing" => o.noise.sigma_bearing = optional(&value)?,
            "sigma_beam" => o.noise.sigma_beam = optional(&value)?,
            "odometry_delay" => {
                o.odometry_delay = if value.is_none() {
                    None
                } else {
                    Some(finite(&value)?)
                };
            }
            "truth_offset" => {
                o.truth_offset = if value.is_none() {
                    None
                } else {
                    Some(finite(&value)?)
                };
            }
            "beam_bias_sigma" => bias[0] = Some(positive(&value)?),
            "beam_bias_tau" => bias[1] = Some(positive(&value)?),
            "estimate" => {
                let what: String = value
                    .extract()
                    .map_err(|_| value_error(name, "expected a string"))?;
                o.estimation = match what.as_str() {
                    "noise" => Estimation::Noise,
                    "delay" => Estimation::Delay,
                    "nothing" => Estimation::Nothing,
                    other => {
                        return Err(value_error(
                            name,
                            format!("{other:?} is not one of \"noise\", \"delay\", \"nothing\""),
                        ));
                    }
                };
            }
            _ => {
                return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                    "replay() got an unexpected keyword argument {name:?}"
                )));
            }
        }
    }
    o.beam_bias = match bias {
        [Some(sigma), Some(tau)] => Some(GaussMarkov { sigma, tau }),
        [None, None] => None,
        _ => {
            return Err(value_error(
                "beam_bias_sigma",
                "give beam_bias_sigma and beam_bias_tau together",
            ));
        }
    };
    Ok(o)
}

/// What a replay returns before it becomes Python objects.
struct Replayed {
    name: String,
    time: Vec<f64>,
    elapsed: Vec<f64>,
    event: Vec<i64>,
    landmark: Vec<i64>,
    nis: Vec<f64>,
    pose: Vec<f64>,
    covariance: Vec<f64>,
    calibration: Vec<f64>,
    dead_reckoning: Vec<f64>,
    truth: Vec<f64>,
    smoothed: Option<(Vec<f64>, Vec<f64>, Vec<f64>)>,
    metrics: String,
}

impl Replayed {
    fn with_capacity(name: String, n: usize, smooth: bool) -> Self {
        Self {
            name,
            time: Vec::with_capacity(n),
            elapsed: Vec::with_capacity(n),
            event: Vec::with_capacity(n),
            landmark: Vec::with_capacity(n),
            nis: Vec::with_capacity(n),
            pose: Vec::with_capacity(3 * n),
            covariance: Vec::with_capacity(9 * n),
            calibration: Vec::with_capacity(4 * n),
            dead_reckoning: Vec::with_capacity(3 * n),
            truth: Vec::with_capacity(3 * n),
            smoothed: smooth.then(|| {
                (
                    Vec::with_capacity(3 * n),
                    Vec::with_capacity(9 * n),
                    Vec::with_capacity(4 * n),
                )
            }),
            metrics: String::new(),
        }
    }

    fn push(&mut self, s: &Step) {
        self.time.push(s.time);
        self.elapsed.push(s.elapsed);
        let (event, landmark, nis) = match s.kind {
            EventKind::Odometry { .. } => (0, -1, f64::NAN),
            EventKind::Sighting {
                sighting, outcome, ..
            } => {
                let nis = match outcome {
                    SightingOutcome::Applied { nis, .. } | SightingOutcome::Gated { nis } => nis,
                    _ => f64::NAN,
                };
                (1, i64::from(sighting.landmark), nis)
            }
            EventKind::Scan {
                sensor, outcome, ..
            } => (
                2,
                i64::from(sensor),
                if outcome.judged() > 0 {
                    outcome.nis
                } else {
                    f64::NAN
                },
            ),
        };
        self.event.push(event);
        self.landmark.push(landmark);
        self.nis.push(nis);
        self.pose.extend_from_slice(s.belief.x.as_slice());
        // Row-major, as numpy stores it (the matrix is symmetric).
        self.covariance.extend_from_slice(s.belief.p.as_slice());
        self.calibration.extend_from_slice(&s.calibration);
        self.dead_reckoning.extend_from_slice(&s.dead_reckoning);
        match s.truth {
            Some(t) => self.truth.extend_from_slice(&[t.x, t.y, t.theta]),
            None => self.truth.extend_from_slice(&[f64::NAN; 3]),
        }
        if let Some((pose, cov, cal)) = &mut self.smoothed {
            match (s.smoothed, s.smoothed_calibration) {
                (Some(b), Some(c)) => {
                    pose.extend_from_slice(b.x.as_slice());
                    cov.extend_from_slice(b.p.as_slice());
                    cal.extend_from_slice(&c);
                }
                _ => {
                    pose.extend_from_slice(&[f64::NAN; 3]);
                    cov.extend_from_slice(&[f64::NAN; 9]);
                    cal.extend_from_slice(&[f64::NAN; 4]);
                }
            }
        }
    }

    fn into_dict<'py>(self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("name", self.name)?;
        d.set_item("time", arrays::vector(py, self.time))?;
        d.set_item("elapsed", arrays::vector(py, self.elapsed))?;
        d.set_item("event", arrays::integers(py, self.event))?;
        d.set_item("landmark", arrays::integers(py, self.landmark))?;
        d.set_item("nis", arrays::vector(py, self.nis))?;
        d.set_item("pose", arrays::matrix(py, self.pose, 3))?;
        d.set_item("covariance", arrays::blocks(py, self.covariance, 3))?;
        d.set_item("calibration", arrays::matrix(py, self.calibration, 4))?;
        d.set_item("dead_reckoning", arrays::matrix(py, self.dead_reckoning, 3))?;
        d.set_item("truth", arrays::matrix(py, self.truth, 3))?;
        if let Some((pose, cov, cal)) = self.smoothed {
            d.set_item("smoothed_pose", arrays::matrix(py, pose, 3))?;
            d.set_item("smoothed_covariance", arrays::blocks(py, cov, 3))?;
            d.set_item("smoothed_calibration", arrays::matrix(py, cal, 4))?;
        }
        d.set_item("metrics", self.metrics)?;
        Ok(d)
    }
}

/// Prepares and replays `log` with `options` on the work thread.
fn replay_log(mut log: Log, options: &Options, stop: &Stop) -> anyhow::Result<Replayed> {
    let prepared = locus_replay::prepare(&mut log, options)
        .with_context(|| format!("settling the noise of {}", log.name))?;
    let cfg = &prepared.settled.config;
    let events = log.odometry.len() + log.sightings.len() + log.scans.len();
    let mut out = Replayed::with_capacity(log.name.clone(), events, cfg.smooth);
    let mut polled = 0_u32;
    let report = locus_replay::replay_until(
        &log,
        cfg,
        || {
            polled = polled.wrapping_add(1);
            polled % 1024 == 0 && stop.asked()
        },
        |step| out.push(step),
    )
    .with_context(|| format!("replaying {}", log.name))?;
    let results = Results::of(&report.summary).with_smoother(report.smoothed.as_ref());
    let section = Section::new(cfg, &report).with_truth_clock(prepared.clock.as_ref());
    out.metrics =
        serde_json::to_string(&Metrics::new(Source::Replay, &log.name, results, &section))?;
    Ok(out)
}

/// Replays the log at `path` (see `locus.replay`).
#[pyfunction]
#[pyo3(signature = (path, format=None, robot=1, topics=None, truth=None, map=None, overrides=None))]
#[allow(clippy::too_many_arguments)]
pub fn replay_file<'py>(
    py: Python<'py>,
    path: PathBuf,
    format: Option<&str>,
    robot: u32,
    topics: Option<PathBuf>,
    truth: Option<PathBuf>,
    map: Option<PathBuf>,
    overrides: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let format = Format::of(format, &path)?;
    let options = options(overrides)?;
    let with = Companions { topics, truth, map };
    let out = interrupt::run(py, move |stop| {
        let log = read(&path, format, robot, &with)?;
        replay_log(log, &options, stop)
    })?
    .map_err(|e| locus_error(&e))?;
    out.into_dict(py)
}

/// Replays a log given as arrays (see `locus.replay`).
#[pyfunction]
#[pyo3(signature = (odometry, sightings=None, landmarks=None, truth=None, start=None, name="arrays".to_string(), overrides=None))]
#[allow(clippy::too_many_arguments)]
pub fn replay_arrays<'py>(
    py: Python<'py>,
    odometry: &Bound<'py, PyAny>,
    sightings: Option<&Bound<'py, PyAny>>,
    landmarks: Option<&Bound<'py, PyAny>>,
    truth: Option<&Bound<'py, PyAny>>,
    start: Option<&Bound<'py, PyAny>>,
    name: String,
    overrides: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let log = log_of_arrays(odometry, sightings, landmarks, truth, start)?;
    let options = options(overrides)?;
    let out = interrupt::run(py, move |stop| {
        let log = Log::from_locus(&name, log)?;
        replay_log(log, &options, stop)
    })?
    .map_err(|e| locus_error(&e))?;
    out.into_dict(py)
}

/// A log from arrays: odometry (N, 3) `t [s], v [m/s], omega [rad/s]`;
/// sightings (M, 4) `t [s], landmark id, range [m], bearing [rad]` (NaN
/// bearing: range only); landmarks (K, 3) `id, x [m], y [m]`; truth (T, 4)
/// `t [s], x [m], y [m], theta [rad]` (NaN heading: positions only); start
/// `x, y, theta`.
fn log_of_arrays(
    odometry: &Bound<'_, PyAny>,
    sightings: Option<&Bound<'_, PyAny>>,
    landmarks: Option<&Bound<'_, PyAny>>,
    truth: Option<&Bound<'_, PyAny>>,
    start: Option<&Bound<'_, PyAny>>,
) -> PyResult<LocusLog> {
    let id = |name: &str, i: usize, v: f64| -> PyResult<u32> {
        if v >= 0.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0 {
            Ok(v as u32)
        } else {
            Err(value_error(
                name,
                format!("row {i}: the id {v} is not a whole number >= 0"),
            ))
        }
    };
    let increasing = |name: &str, times: &[f64]| -> PyResult<()> {
        match times.windows(2).position(|w| w[1] < w[0]) {
            Some(i) => Err(value_error(
                name,
                format!(
                    "row {}: time {} s is before the row above's",
                    i + 1,
                    times[i + 1]
                ),
            )),
            None => Ok(()),
        }
    };
    let mut log = LocusLog::default();
    let odo = arrays::rows("odometry", odometry, 3, &[])?;
    increasing("odometry", &odo.iter().map(|r| r[0]).collect::<Vec<_>>())?;
    log.odometry = odo
        .iter()
        .map(|r| Odometry {
            time: r[0],
            v: r[1],
            omega: r[2],
        })
        .collect();
    if let Some(s) = sightings {
        for (i, r) in arrays::rows("sightings", s, 4, &[3])?.iter().enumerate() {
            if r[2] < 0.0 {
                return Err(value_error(
                    "sightings",
                    format!("row {i}: the range {} m is negative", r[2]),
                ));
            }
            log.measurements.push(LandmarkMeasurement {
                time: r[0],
                id: id("sightings", i, r[1])?,
                range: r[2],
                bearing: (!r[3].is_nan()).then_some(r[3]),
            });
        }
    }
    if let Some(l) = landmarks {
        for (i, r) in arrays::rows("landmarks", l, 3, &[])?.iter().enumerate() {
            log.landmarks.push(MapLandmark {
                id: id("landmarks", i, r[0])?,
                x: r[1],
                y: r[2],
            });
        }
    }
    if let Some(t) = truth {
        let rows = arrays::rows("truth", t, 4, &[3])?;
        increasing("truth", &rows.iter().map(|r| r[0]).collect::<Vec<_>>())?;
        let poses: Vec<TruthPose> = rows
            .iter()
            .map(|r| TruthPose {
                time: r[0],
                x: r[1],
                y: r[2],
                theta: r[3],
            })
            .collect();
        let no_heading = poses.iter().filter(|p| p.theta.is_nan()).count();
        log.truth = if no_heading == poses.len() {
            Groundtruth::positions(poses)
        } else if no_heading == 0 {
            Groundtruth::new(poses)
        } else {
            return Err(value_error(
                "truth",
                "give a heading in every row, or NaN in every row (positions only)",
            ));
        }
        .expect("times checked in order");
    }
    if let Some(s) = start {
        let [x, y, theta] = arrays::fixed::<3>("start", s)?;
        let time = log.odometry.first().map_or(0.0, |o| o.time);
        log.start = Some(TruthPose { time, x, y, theta });
    }
    Ok(log)
}
