//! What a user sets of a replay ([`Options`]), with `locus replay`'s
//! defaults, and the way from a log to the settings it is replayed with
//! ([`prepare`]): the start pose given, the truth put on the sensors'
//! clock ([`crate::truth_clock`]), the noise settled ([`crate::policy`]).
//! The command line (`locus replay`'s flags) and the Python package
//! (`locus.replay`) both fill an [`Options`], so they replay alike.

use locus_logs::mrclam::TruthPose;
use locus_logs::noise::NoiseRecords;
use locus_models::plausible::Limits;

use crate::policy::{Estimation, Overrides, Settled};
use crate::truth_clock::TruthClock;
use crate::{Beams, Calibration, Config, Error, GaussMarkov, Log, Start};

/// The standard deviation of a calibration state held by
/// [`Options::hold_calibration`] (in the state's unit): small enough that
/// the covariance it leaves is below rounding against the pose's (a
/// turn-rate bias of 1e-6 rad/s, the default's held value, grows a heading
/// uncertainty of 1.6e-4 rad over 160 s; one of 1e-12, 1.6e-10 rad).
pub const HELD_STD: f64 = 1e-12;

/// A replay's settings as a user gives them; [`Options::default`] is
/// `locus replay` with no flags. Each field is the flag of the same name
/// (docs/replay.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Chi-square gate confidence in (0, 1); `None`: no gate.
    pub gate: Option<f64>,
    /// Student-t degrees of freedom of the sightings' noise; `None`:
    /// Gaussian sightings.
    pub robust_dof: Option<f64>,
    /// Also run the Rauch-Tung-Striebel smoother.
    pub smooth: bool,
    /// Find the initial pose from the first sightings.
    pub start_from_sightings: bool,
    /// Initial forward-speed scale factor.
    pub v_scale: f64,
    /// Initial turn-rate scale factor.
    pub omega_scale: f64,
    /// Hold the calibration states at their initial values ([`HELD_STD`]).
    pub hold_calibration: bool,
    /// Standard deviations of the initial estimate: x (m), y (m), heading
    /// (rad); `None`: [`Config::default`]'s.
    pub initial_std: Option<[f64; 3]>,
    /// Where the robot starts, x (m), y (m), heading (rad), at the first
    /// odometry time: replaces the log's start pose and the truth's.
    pub start: Option<[f64; 3]>,
    /// Beams a scan spends at most.
    pub beams_per_scan: u32,
    /// Top speed (m/s), turn rate (rad/s) and gap between odometry records
    /// (s) a record may have before it is refused as implausible.
    pub limits: Limits,
    /// Noise levels given (each wins over the log's record and any
    /// estimate).
    pub noise: NoiseRecords,
    /// The odometry delay, s; `None`: estimated.
    pub odometry_delay: Option<f64>,
    /// The beams' range bias; `None`: searched with the beams' noise.
    pub beam_bias: Option<GaussMarkov<f64>>,
    /// What to estimate from the log.
    pub estimation: Estimation,
    /// How late the truth's stamps are, s; `None`: measured.
    pub truth_offset: Option<f64>,
}

impl Default for Options {
    fn default() -> Self {
        let defaults = Config::default();
        Self {
            gate: defaults.gate,
            robust_dof: Some(4.0),
            smooth: false,
            start_from_sightings: false,
            v_scale: 1.0,
            omega_scale: 1.0,
            hold_calibration: false,
            initial_std: None,
            start: None,
            beams_per_scan: Beams::default().per_scan,
            limits: Limits::GENERIC,
            noise: NoiseRecords::default(),
            odometry_delay: None,
            beam_bias: None,
            estimation: Estimation::Noise,
            truth_offset: None,
        }
    }
}

impl Options {
    /// The replay's settings other than the noise and the odometry delay
    /// (those [`prepare`] settles).
    #[must_use]
    pub fn config(&self) -> Config {
        let defaults = Config::default();
        let mut calibration = Calibration {
            initial: [self.v_scale, self.omega_scale, 0.0, 0.0],
            ..Calibration::default()
        };
        let mut beams = Beams {
            per_scan: self.beams_per_scan,
            ..Beams::default()
        };
        if self.hold_calibration {
            calibration.std = [HELD_STD; 4];
            calibration.walk = [0.0; 4];
            beams.bias = GaussMarkov {
                sigma: HELD_STD,
                tau: f64::INFINITY,
            };
        }
        Config {
            gate: self.gate,
            robust_dof: self.robust_dof,
            smooth: self.smooth,
            start: if self.start_from_sightings {
                Start::Sightings
            } else {
                Start::Log
            },
            calibration,
            beams,
            initial_std: self.initial_std.unwrap_or(defaults.initial_std),
            limits: self.limits,
            ..defaults
        }
    }

    /// What the options settle of the noise and the odometry delay, and
    /// what they leave for [`crate::policy`] to estimate.
    #[must_use]
    pub fn overrides(&self) -> Overrides {
        Overrides {
            noise: self.noise,
            odometry_delay: self.odometry_delay,
            beam_bias: self.beam_bias,
            estimation: self.estimation,
        }
    }
}

/// A log made ready to replay: the settings settled, and what was done to
/// the truth's clock.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The settings, and where each came from.
    pub settled: Settled,
    /// The truth's clock (`None`: a log without truth or readings to
    /// measure it by).
    pub clock: Option<TruthClock>,
}

/// Makes `log` ready to replay with `options`, as `locus replay` does:
/// the start pose given replaces the log's, the truth is put on the
/// sensors' clock, and the noise and the odometry delay are settled.
///
/// # Errors
/// A setting the log cannot be replayed with (see
/// [`crate::policy::settle`]).
pub fn prepare(log: &mut Log, options: &Options) -> Result<Prepared, Error> {
    if let Some([x, y, theta]) = options.start {
        let time = log.odometry.first().map_or(0.0, |o| o.time);
        log.start = Some(TruthPose { time, x, y, theta });
    }
    let config = options.config();
    let clock = crate::truth_clock::settle(log, &config, options.truth_offset);
    let settled = crate::policy::settle(log, &config, &options.overrides())?;
    Ok(Prepared { settled, clock })
}
