//! Replay of recorded robot logs through Locus's EKF.
//!
//! A [`Log`] (from an MRCLAM dataset or a Locus CSV log, see
//! `docs/log-format.md`) is replayed by [`replay`]:
//!
//! * **Time.** Odometry (commanded or measured `v`, `omega`, held from one
//!   record to the next) and landmark sightings are merged in time order.
//!   Each record is an *event*, kept in the history of Locus's running
//!   filter ([`locus_core::RunningFilter`]); between two events it predicts with
//!   the [`Unicycle`] model over the time between them. A sighting arrives
//!   at [`Sighting::arrival`] (after the odometry up to that time); if it is
//!   older than the filter's time, the replay goes back to the belief just
//!   before the sighting's own time in a short history
//!   ([`Config::horizon`] seconds), applies it there and re-runs the later
//!   events. The estimates are therefore those of an in-order replay (to
//!   rounding: the same operations in the same order, so in practice
//!   bit-for-bit). A sighting older than the history is counted
//!   ([`Report::too_late`]) and not applied.
//! * **Events in canonical order.** Events are kept sorted by time, then
//!   odometry before sightings, then sightings by landmark, range and
//!   bearing; odometry records at equal times keep their log order.
//! * **Correction.** Each landmark sighting is one range-bearing
//!   correction from the sensor where the log's `sensor` record mounts it
//!   ([`Log::sensor`]; the robot's centre by default), with the bearing
//!   bias state ([`CalibratedRangeBearing`]); a range-only sighting (a UWB
//!   beacon's) is a 1-D range correction from the same sensor
//!   ([`CalibratedRange`]), gated on chi-square with 1 dof; both weighted
//!   as Student-t noise
//!   ([`Config::robust_dof`]). Sightings of landmarks not in the map are
//!   counted and skipped; robot-to-robot sightings never reach the replay
//!   (the MRCLAM log splits them off).
//! * **Calibration.** The state holds the pose and the odometry and sensor
//!   calibration ([`CalibratedUnicycle`](locus_models::calibrated_unicycle::CalibratedUnicycle):
//!   scale factors of the logged speed and turn rate, turn-rate and bearing
//!   biases), estimated with it ([`Config::calibration`]).
//! * **Smoothing.** With [`Config::smooth`], the Rauch-Tung-Striebel
//!   smoother runs backwards over the final forward pass; each step then
//!   carries its smoothed pose and the report the smoother's figures. It
//!   works in segments re-made from checkpoints of the forward pass
//!   ([`replay_in_segments`]): its memory grows as the square root of the
//!   log's length.
//! * **Gating with recovery.** The running filter's chi-square gate
//!   ([`Config::gate`]) rejects
//!   outliers. A filter that has become over-confident would reject every
//!   later sighting; so after [`Config::recover_after`] consecutive
//!   rejections the covariance is multiplied by [`Config::inflation`] and
//!   the sighting is tried again (and again at each further rejection, so
//!   the inflation compounds until a sighting fits). The calibration
//!   states with no random walk are held: the inflation leaves them as
//!   they are ([`locus_core::Recovery`]).
//! * **Initial pose.** The log's start pose, else the ground truth at the
//!   first odometry time (for a truth of positions only, its position and
//!   the heading of its direction of motion, [`initial::heading_from_truth`],
//!   if it moves), else the pose the first sightings fix
//!   ([`initial`]); [`Config::start`] can ask for the last whatever the
//!   log gives. [`Report::started_from`] says which.
//! * **Ground truth.** Each event's estimate is compared with the ground
//!   truth interpolated at its time (events where the truth has a gap wider
//!   than [`Config::truth_max_gap`] or has ended are not compared), beside
//!   dead reckoning from the same start with the same inputs. The
//!   figures are accumulated by `locus-eval`'s [`Tally`] into its
//!   [`Summary`](locus_eval::Summary), so they read as `locus run`'s.
//!
//! Units: SI (m, rad, s); headings wrapped to (-pi, pi].
//!
//! [`Unicycle`]: locus_models::unicycle::Unicycle
//! [`CalibratedRangeBearing`]: locus_models::calibrated_range_bearing::CalibratedRangeBearing
//! [`CalibratedRange`]: locus_models::calibrated_range::CalibratedRange
//! [`Tally`]: locus_eval::Tally

extern crate alloc;

pub mod beam;
mod config;
pub mod csv_out;
mod dead_reckoning;
mod describe;
pub mod drift;
mod engine;
mod error;
mod event;
mod filter;
pub mod fleet;
pub mod initial;
mod instants;
mod ir_pair;
mod linearised_at;
pub mod log;
pub mod noise;
pub mod options;
pub mod policy;
pub mod rail;
pub mod refusals;
mod report;
pub mod results;
mod scan_align;
mod segments;
mod smoother;
mod start;
mod step;
pub mod truth_clock;

pub use config::{Beams, Calibration, Config, Start};
pub use error::Error;
pub use filter::{NIS_CAP, NIS_CAP_RANGE, STATE, StateMatrix, StateVector};
pub use locus_models::calibrated_unicycle::GaussMarkov;
pub use log::{Landmark, Log, RefusedRecord, RefusedTime, Sighting, TIME_TOLERANCE, TimeProblem};
pub use options::{Options, Prepared, prepare};
pub use refusals::{Refusal, Refusals};
pub use report::{Report, StartDisagreement, StartedFrom};
pub use segments::{replay, replay_in_segments, replay_until, smoothing_segment};
pub use step::{EventKind, ScanOutcome, SightingOutcome, Step, Unusable};
