//! The host's configuration and its checks.

use core::time::Duration;

use locus_models::{LocaliserConfig, Segment};

use crate::Error;
use crate::plausible::Limits;

/// Width of the link's encoder counts (bits): they wrap modulo `2^32`.
/// [`HostConfig::localiser`] must use it.
pub const COUNTER_BITS: u32 = 32;

/// Configuration of the host.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostConfig {
    /// The robot's geometry, encoder and IR pair, the filter's `Q`, `R`,
    /// gate and initial belief; `counter_bits` must be [`COUNTER_BITS`].
    pub localiser: LocaliserConfig<f64>,
    /// Whether the filter uses the IR readings (`false`: odometry only).
    pub use_ir: bool,
    /// The walls the IR pair is associated with (m, world frame): the
    /// square arena around the path.
    pub walls: [Segment<f64>; 4],
    /// The path controller's parameters.
    pub control: locus_control::Config,
    /// Laps of the square path to drive (>= 1).
    pub laps: usize,
    /// Interval of the handshake's zero-speed command. Default 50 ms.
    pub resend: Duration,
    /// Wall time to wait for the robot's first telemetry. Default 10 s.
    pub handshake: Duration,
    /// Wall time without telemetry after which the run ends (after the laps
    /// are done, or if the robot goes silent). Default 0.5 s.
    pub quiet: Duration,
    /// Bucket of the clock estimator's minimum-delay filter (s of host
    /// time); the window is 64 buckets. Default 0.05 s.
    pub clock_bucket: f64,
    /// What a telemetry packet may say (top wheel speed, longest period,
    /// longest IR reading). Default [`Limits::PAPER_001`].
    pub limits: Limits,
}

impl HostConfig {
    /// A host running `localiser` in the arena `walls`, with IR, the
    /// default path controller, 2 laps and the default timing.
    pub fn new(localiser: LocaliserConfig<f64>, walls: [Segment<f64>; 4]) -> Self {
        Self {
            localiser,
            use_ir: true,
            walls,
            control: locus_control::Config::default(),
            laps: 2,
            resend: Duration::from_millis(50),
            handshake: Duration::from_secs(10),
            quiet: Duration::from_millis(500),
            clock_bucket: 0.05,
            limits: Limits::PAPER_001,
        }
    }

    /// Checks the values the host relies on.
    ///
    /// # Errors
    /// [`Error::Config`] naming the first invalid value;
    /// [`Error::OutOfRange`] for a setting outside its range of
    /// [`locus_models::settings`].
    pub fn validate(&self) -> Result<(), Error> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let l = &self.localiser;
        let c = &self.control;
        let checks = [
            (self.laps > 0, "laps must be >= 1"),
            (
                l.counter_bits == COUNTER_BITS,
                "localiser.counter_bits must be 32 (the link's counts)",
            ),
            (control_ok(c), "control values must be finite and > 0"),
            (
                pos(self.clock_bucket),
                "clock_bucket must be finite and > 0 s",
            ),
        ];
        if let Some((_, what)) = checks.into_iter().find(|(ok, _)| !ok) {
            return Err(Error::Config(what));
        }
        self.limits.validate().map_err(Error::Config)?;
        l.validate().map_err(localiser_error)?;
        within_settings(l, c)
    }
}

/// `Ok(())` if the user's settings among `l` and `c` (`Q`, `R`, the gate,
/// the controller's speeds and gains) are within their ranges of
/// [`locus_models::settings`].
///
/// # Errors
/// [`Error::OutOfRange`] for the first that is not.
pub(super) fn within_settings(
    l: &LocaliserConfig<f64>,
    c: &locus_control::Config,
) -> Result<(), Error> {
    use locus_models::settings as s;
    let table = [
        (s::Q11, l.q11),
        (s::Q22, l.q22),
        (s::R11, l.r11),
        (s::R22, l.r22),
        (s::GATE, l.gate_confidence.unwrap_or(0.0)),
        (s::V_REF, c.v_ref),
        (s::W_REF, c.w_ref),
        (s::K_CROSS, c.k_cross),
        (s::K_HEADING, c.k_heading),
        (s::K_POS, c.k_pos),
    ];
    match table.into_iter().find(|(limit, v)| !limit.contains(*v)) {
        Some((limit, value)) => Err(Error::OutOfRange { limit, value }),
        None => Ok(()),
    }
}

/// Whether every controller value is finite and positive (what the path
/// controller divides by and saturates with).
pub(super) fn control_ok(c: &locus_control::Config) -> bool {
    [
        c.v_ref,
        c.w_ref,
        c.k_cross,
        c.k_heading,
        c.k_pos,
        c.pos_tol,
        c.heading_tol,
    ]
    .into_iter()
    .all(|v| v.is_finite() && v > 0.0)
}

/// A refused localiser configuration as the host's [`Error::Config`].
pub(super) fn localiser_error(e: locus_core::Error) -> Error {
    match e {
        locus_core::Error::InvalidParameter(what) => Error::Config(what),
        _ => Error::Config("invalid localiser configuration"),
    }
}
