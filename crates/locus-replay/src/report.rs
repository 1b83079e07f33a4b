//! What a replay did, besides the per-step figures.

use locus_core::Belief;
use locus_eval::Summary;

/// What a replay did, besides the per-step figures.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// Errors against the ground truth (over the steps it covers), as for
    /// `locus run`; NaN (printed "n/a", `null` in JSON) for every figure
    /// that needs the truth when no step was compared. The tally takes
    /// every event: `steps` counts them all, `compared` those the truth
    /// covers; `readings` counts all the sightings replayed, `associated`
    /// those the gate judged (applied or gated), `applied` those applied;
    /// `acceptance` is NaN when none was judged.
    pub summary: Summary,
    /// The smoother's figures against the ground truth (with
    /// [`Config::smooth`](crate::Config::smooth)).
    pub smoothed: Option<Summary>,
    /// Events replayed (odometry records + landmark sightings).
    pub steps: usize,
    /// Events compared with ground truth.
    pub compared: usize,
    /// Odometry records.
    pub odometry: usize,
    /// Landmark sightings in the log (all of them, compared or not).
    pub sightings: usize,
    /// Sightings applied (including after recovery).
    pub applied: usize,
    /// Applied sightings whose Student-t weight was below 1 (their noise
    /// inflated as outliers-to-be).
    pub down_weighted: usize,
    /// Sightings rejected by the gate.
    pub gated: usize,
    /// Covariance inflations (recoveries: at each, the sighting was retried).
    pub inflations: usize,
    /// Sightings applied only after an inflation.
    pub recovered: usize,
    /// Sightings of landmarks not in the map.
    pub not_in_map: usize,
    /// Sightings where the model predicts no measurement.
    pub no_measurement: usize,
    /// Sightings refused because the filter cannot use them (see
    /// [`Unusable`](crate::Unusable)); each is a step with that outcome.
    pub unusable: usize,
    /// Sightings refused before the replay for an implausible time stamp
    /// ([`Log::refused_times`](crate::Log::refused_times)).
    pub implausible_time: usize,
    /// Odometry records refused as implausible
    /// ([`Log::odometry_problem`](crate::Log::odometry_problem)): not
    /// applied, the velocities before each held.
    pub implausible_odometry: usize,
    /// Every record refused (noise and odometry records with implausible
    /// values, sightings with implausible time stamps, sightings the
    /// filter cannot use), the first [`KEPT`](crate::refusals::KEPT) with
    /// their line.
    pub refusals: crate::refusals::Refusals,
    /// Robot-to-robot sightings left out by the log.
    pub robot_sightings: usize,
    /// Sightings of unknown targets left out by the log.
    pub unknown_sightings: usize,
    /// Sightings that arrived out of order and were applied at their own
    /// time by re-running the history.
    pub late: usize,
    /// Sightings older than the history (or than the first odometry),
    /// not applied.
    pub too_late: usize,
    /// Scans of beam sensors replayed.
    pub scans: usize,
    /// What their beams did, summed over the scans.
    pub beams: crate::ScanOutcome,
    /// Negative log-likelihood of the innovations (natural log, without
    /// the constant `ln 2 pi` per sighting): the sum over the sightings
    /// that reached the filter of `(ln det S + min(NIS, NIS_CAP)) / 2`, `S`
    /// and the NIS against the belief before the sighting. The objective
    /// `locus tune` minimises; the cap keeps gross outliers from dominating.
    pub innovation_nll: f64,
    /// The final belief of the pose.
    pub final_belief: Belief<f64, 3>,
    /// The filter's final calibration, `(mean, standard deviation)` of the
    /// forward-speed scale, turn-rate scale, turn-rate bias (rad/s) and
    /// bearing bias (rad).
    pub calibration: [(f64, f64); 4],
    /// The smoother's calibration at the first event (the estimate from the
    /// whole log), with [`Config::smooth`](crate::Config::smooth).
    pub smoothed_calibration: Option<[(f64, f64); 4]>,
    /// Where the initial pose came from.
    pub started_from: StartedFrom,
    /// When the replay started from the log's `start` pose and the log's
    /// first sightings fix a pose that contradicts it (beyond the 99.9 %
    /// chi-square(3) bound of both uncertainties): the two poses. A
    /// start record that is wrong is the user's to notice; the replay
    /// keeps it.
    pub start_disagreement: Option<StartDisagreement>,
    /// With [`Config::smooth`](crate::Config::smooth): the most steps the
    /// smoother held at once (one segment's, see
    /// [`replay_in_segments`](crate::replay_in_segments)); 0 without.
    pub smoothing_held: usize,
    /// With [`Config::smooth`](crate::Config::smooth): the checkpoints of
    /// the forward pass the smoother kept (copies of the running filter,
    /// one per segment after the first); 0 without.
    pub smoothing_checkpoints: usize,
}

/// Where a replay's initial pose came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StartedFrom {
    /// The log's `start` pose.
    Log,
    /// The ground truth at the first odometry time.
    Truth,
    /// The position of a ground truth without heading at the first
    /// odometry time, the heading from its direction of motion
    /// ([`crate::initial::heading_from_truth`]).
    TruthPosition(crate::initial::TruthHeading),
    /// The first sightings ([`crate::initial`]).
    Sightings(crate::initial::Fix),
}

/// The log's start pose against the pose its first sightings fix
/// ([`crate::initial::from_sightings`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartDisagreement {
    /// The log's start: x, y (m), heading (rad).
    pub log: [f64; 3],
    /// The sightings' fix at the first odometry time: x, y (m), heading
    /// (rad).
    pub sightings: [f64; 3],
    /// Their distance in standard deviations of both uncertainties
    /// (the square root of [`crate::initial::Fix::distance2`]); above
    /// `sqrt(`[`crate::initial::DISAGREE`]`)`.
    pub sigma: f64,
}

impl Report {
    /// Share of the sightings that reached the filter which the gate
    /// rejected (0 if none reached it).
    #[must_use]
    #[allow(clippy::cast_precision_loss)]
    pub fn gated_share(&self) -> f64 {
        let n = self.applied + self.gated;
        if n == 0 {
            0.0
        } else {
            self.gated as f64 / n as f64
        }
    }
}
