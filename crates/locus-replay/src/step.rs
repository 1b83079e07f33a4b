//! One replayed event as the sink sees it: what it was, what the filter did
//! with it, the estimate after it, its CSV row and its evaluation sample.

use locus_core::nalgebra::Vector3;
use locus_core::{Belief, Pose};
use locus_eval::Sample;
use locus_logs::mrclam::TruthPose;

use crate::Sighting;

/// What happened to a sighting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SightingOutcome {
    /// Corrected the belief (NIS of the applied correction; `recovered`:
    /// applied only after the covariance was inflated).
    Applied {
        /// NIS of the correction (2 dof, 1 for a range-only sighting),
        /// against the nominal noise.
        nis: f64,
        /// Whether the covariance was inflated before it was applied.
        recovered: bool,
        /// The Student-t weight it was applied with, in (0, 1].
        weight: f64,
    },
    /// Rejected by the gate (NIS against the belief it was tried on).
    Gated {
        /// NIS (2 dof, 1 for a range-only sighting).
        nis: f64,
    },
    /// The landmark is not in the map.
    NotInMap,
    /// The model predicts no measurement (the robot on the landmark).
    NoMeasurement,
    /// Refused: the filter cannot use it (the belief is unchanged).
    Unusable(Unusable),
}

/// Why the filter cannot use a sighting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Unusable {
    /// Its range is above [`Config::max_range`](crate::Config::max_range).
    RangeAbove {
        /// The bound, m.
        max: f64,
    },
    /// The correction failed on it: its innovation covariance is not
    /// positive definite, or a value of the correction is not finite
    /// (the filter's own typed error).
    Filter(locus_core::Error),
}

impl Unusable {
    /// The filter's errors that condemn the sighting rather than the
    /// belief: a non-finite measurement, noise or model output, an
    /// innovation or noise covariance that is not positive definite.
    #[must_use]
    pub fn of(e: locus_core::Error) -> Option<Self> {
        use locus_core::{Error, Input};
        match e {
            Error::InnovationNotPositiveDefinite
            | Error::NoiseNotPositiveDefinite
            | Error::NonFinite(
                Input::Measurement | Input::MeasurementNoise | Input::MeasurementModel,
            ) => Some(Unusable::Filter(e)),
            _ => None,
        }
    }
}

impl core::fmt::Display for Unusable {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Unusable::RangeAbove { max } => write!(f, "range above {max} m"),
            Unusable::Filter(e) => write!(f, "{e}"),
        }
    }
}

/// What happened to a scan's beams: how many the scan had, how many the
/// replay spent on it ([`Beams::per_scan`](crate::Beams::per_scan)), and
/// of those, what each did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ScanOutcome {
    /// Beams in the scan.
    pub beams: u32,
    /// Beams chosen (spread evenly over the scan).
    pub chosen: u32,
    /// Chosen beams with no return or no valid reading (skipped).
    pub no_return: u32,
    /// Chosen beams whose cast from the estimate meets nothing within
    /// the sensor's range, or meets it grazing or from behind (skipped).
    pub no_surface: u32,
    /// Chosen beams that read far shorter than the map (something not in
    /// the map: skipped).
    pub short: u32,
    /// Beams that corrected the belief.
    pub applied: u32,
    /// Of those, applied with a Student-t weight below 1.
    pub down_weighted: u32,
    /// Beams the gate rejected.
    pub gated: u32,
    /// Beams the filter could not use (refused, the belief unchanged).
    pub unusable: u32,
    /// Scans aligned to the map (`scan_align.rs`) and corrected there,
    /// their beams cast from the aligned pose and linearised at it: 1 for
    /// one scan, summed in a report.
    pub aligned: u32,
    /// Sum of the NIS of the beams that reached the gate (applied or
    /// gated; chi-square with [`ScanOutcome::judged`] dof if the noise is
    /// right).
    pub nis: f64,
}

impl ScanOutcome {
    /// Beams that reached the gate (applied or gated).
    #[must_use]
    pub fn judged(&self) -> u32 {
        self.applied + self.gated
    }
}

/// The kind of an event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EventKind {
    /// An odometry record (the input from now on, after scaling).
    Odometry {
        /// Forward speed as logged, m/s.
        v: f64,
        /// Turn rate as logged, rad/s.
        omega: f64,
    },
    /// A landmark sighting.
    Sighting {
        /// The sighting.
        sighting: Sighting,
        /// What the filter did with it.
        outcome: SightingOutcome,
        /// Its line in the log file, if known.
        line: Option<usize>,
    },
    /// A scan of a beam sensor.
    Scan {
        /// Its index in [`Log::scans`](crate::Log::scans).
        index: usize,
        /// The beam sensor's id.
        sensor: u32,
        /// What its beams did.
        outcome: ScanOutcome,
        /// Its line in the log file, if known.
        line: Option<usize>,
    },
}

/// One replayed event with the final estimate after it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Index in canonical (time) order, from 0.
    pub index: usize,
    /// The event's time, s (as in the log).
    pub time: f64,
    /// Time since the first odometry record, s.
    pub elapsed: f64,
    /// The event.
    pub kind: EventKind,
    /// The belief of the pose after the event.
    pub belief: Belief<f64, 3>,
    /// The filter's calibration after the event: forward-speed scale,
    /// turn-rate scale, turn-rate bias (rad/s), bearing bias (rad).
    pub calibration: [f64; 4],
    /// The smoothed belief of the pose (with `Config::smooth`).
    pub smoothed: Option<Belief<f64, 3>>,
    /// The smoothed calibration, in [`Step::calibration`]'s order (with
    /// `Config::smooth`).
    pub smoothed_calibration: Option<[f64; 4]>,
    /// Dead reckoning (odometry alone) `[x, y, theta]` at this time.
    pub dead_reckoning: [f64; 3],
    /// Ground truth interpolated at this time, if covered.
    pub truth: Option<TruthPose>,
}

impl Step {
    /// The CSV header of [`Step::csv_row`] (units in the names).
    #[must_use]
    pub fn csv_header() -> &'static str {
        "index,time_s,elapsed_s,event,landmark,range_m,bearing_rad,nis,nis_dof,applied,\
         x_m,y_m,theta_rad,var_x_m2,cov_xy_m2,cov_xtheta_mrad,var_y_m2,cov_ytheta_mrad,\
         var_theta_rad2,odo_x_m,odo_y_m,odo_theta_rad,true_x_m,true_y_m,true_theta_rad"
    }

    /// The step as one CSV line (empty fields where not applicable, no line
    /// end): [`Step::write_csv_row`] into a new `String`.
    #[must_use]
    pub fn csv_row(&self) -> String {
        let mut row = String::with_capacity(400);
        self.write_csv_row(&mut row);
        row
    }

    /// Appends the step to `out` as one CSV line, the columns of
    /// [`Step::csv_header`] (empty fields where not applicable, no line
    /// end). Numbers are written as Rust's `Display` writes them (shortest
    /// round-trip digits, no exponent), by `locus_logs::decimal::push_f64`,
    /// with no allocation beyond growing `out`; clear and reuse one `String`
    /// across steps.
    pub fn write_csv_row(&self, out: &mut String) {
        use core::fmt::Write as _;
        use locus_logs::decimal::push_f64;
        let _ = write!(out, "{},", self.index);
        push_f64(out, self.time);
        out.push(',');
        push_f64(out, self.elapsed);
        match self.kind {
            EventKind::Odometry { .. } => out.push_str(",odometry,,,,,,"),
            EventKind::Sighting {
                sighting, outcome, ..
            } => {
                let _ = write!(out, ",sighting,{},", sighting.landmark);
                push_f64(out, sighting.range);
                out.push(',');
                if let Some(b) = sighting.bearing {
                    push_f64(out, b);
                }
                out.push(',');
                let (nis, applied) = match outcome {
                    SightingOutcome::Applied { nis, recovered, .. } => {
                        (Some(nis), if recovered { "recovered" } else { "1" })
                    }
                    SightingOutcome::Gated { nis } => (Some(nis), "0"),
                    SightingOutcome::NotInMap => (None, "not-in-map"),
                    SightingOutcome::NoMeasurement => (None, "no-measurement"),
                    SightingOutcome::Unusable(_) => (None, "unusable"),
                };
                if let Some(nis) = nis {
                    push_f64(out, nis);
                    let _ = write!(out, ",{}", sighting.dof());
                } else {
                    out.push(',');
                }
                out.push(',');
                out.push_str(applied);
            }
            // A scan: the sensor in the landmark column, the NIS summed
            // over the beams judged with their count as its dof, the
            // beams applied.
            EventKind::Scan {
                sensor, outcome, ..
            } => {
                let _ = write!(out, ",scan,{sensor},,,");
                if outcome.judged() > 0 {
                    push_f64(out, outcome.nis);
                    let _ = write!(out, ",{}", outcome.judged());
                } else {
                    out.push(',');
                }
                let _ = write!(out, ",{}", outcome.applied);
            }
        }
        let x = &self.belief.x;
        let p = &self.belief.p;
        let d = &self.dead_reckoning;
        let estimate = [
            x[0],
            x[1],
            x[2],
            p[(0, 0)],
            p[(0, 1)],
            p[(0, 2)],
            p[(1, 1)],
            p[(1, 2)],
            p[(2, 2)],
            d[0],
            d[1],
            d[2],
        ];
        for v in estimate {
            out.push(',');
            push_f64(out, v);
        }
        match self.truth {
            Some(t) => {
                for v in [t.x, t.y, t.theta] {
                    out.push(',');
                    // A truth with no heading leaves its field empty.
                    if !v.is_nan() {
                        push_f64(out, v);
                    }
                }
            }
            None => out.push_str(",,,"),
        }
    }

    /// The CSV header of [`Step::write_smoothed_csv_row`] (units in the
    /// names).
    #[must_use]
    pub fn smoothed_csv_header() -> &'static str {
        "index,time_s,x_m,y_m,theta_rad,var_x_m2,cov_xy_m2,var_y_m2,var_theta_rad2,\
         v_scale,omega_scale,omega_bias_rad_per_s,bearing_bias_rad"
    }

    /// Appends the step's smoothed pose, its covariance and the smoothed
    /// calibration as one CSV line (no line end) to `out`; nothing if the
    /// step has no smoothed estimate.
    pub fn write_smoothed_csv_row(&self, out: &mut String) {
        use core::fmt::Write as _;
        use locus_logs::decimal::push_f64;
        let (Some(b), Some(c)) = (self.smoothed, self.smoothed_calibration) else {
            return;
        };
        let _ = write!(out, "{}", self.index);
        let p = &b.p;
        for v in [
            self.time,
            b.x[0],
            b.x[1],
            b.x[2],
            p[(0, 0)],
            p[(0, 1)],
            p[(1, 1)],
            p[(2, 2)],
            c[0],
            c[1],
            c[2],
            c[3],
        ] {
            out.push(',');
            push_f64(out, v);
        }
    }

    /// Whether a measurement arrived at this step (a sighting), and the
    /// correction it made if it reached the gate: its NIS, the NIS's
    /// degrees of freedom and whether it was applied ([`Sample`]'s
    /// `measured` and `correction`).
    #[must_use]
    pub fn measurement(&self) -> (bool, Option<(f64, u32, bool)>) {
        match self.kind {
            EventKind::Odometry { .. } => (false, None),
            EventKind::Sighting {
                outcome, sighting, ..
            } => match outcome {
                SightingOutcome::Applied { nis, .. } => (true, Some((nis, sighting.dof(), true))),
                SightingOutcome::Gated { nis } => (true, Some((nis, sighting.dof(), false))),
                SightingOutcome::NotInMap
                | SightingOutcome::NoMeasurement
                | SightingOutcome::Unusable(_) => (true, None),
            },
            EventKind::Scan { outcome, .. } => (
                true,
                (outcome.judged() > 0)
                    .then(|| (outcome.nis, outcome.judged(), outcome.applied > 0)),
            ),
        }
    }

    /// The figures `locus run` summarises and draws, if the step has a
    /// ground truth to compare with (NEES against it, 3 dof).
    #[must_use]
    pub fn sample(&self) -> Option<Sample> {
        self.sample_of(&self.belief)
    }

    /// As [`Step::sample`], for another estimate of this step's pose (the
    /// smoothed one).
    #[must_use]
    pub fn sample_of(&self, belief: &Belief<f64, 3>) -> Option<Sample> {
        let t = self.truth?;
        let d = &self.dead_reckoning;
        let (measured, correction) = self.measurement();
        Some(Sample::planar(
            self.index,
            self.elapsed,
            &Pose::from_vector(&Vector3::new(t.x, t.y, t.theta)),
            belief,
            Some(&Pose::from_vector(&Vector3::new(d[0], d[1], d[2]))),
            correction,
            measured,
        ))
    }
}
