//! The settings of paper 001's loop that a user may set (a scenario file,
//! the teaching UI, the robot-link host), each with its one accepted range.
//! The simulator's configuration check, the host's live setters and the
//! teaching UI (which sends this table to the page) all read these
//! constants, so a value is accepted by all of them or by none.
//!
//! The ranges are wide enough for the teaching guide's extremes (`Q` of
//! 1e-14 in step d, `Q22` of 1e4 in step e) and narrow enough to keep a run
//! meaningful for the spec's robot (`MODELS.md` section 3: a Lego NXT on a
//! 2 m square arena, IR sensors with a useful range of 4-30 cm).

/// The accepted range of a setting: finite and in `min..=max`, in `unit`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Limit {
    /// The setting's name (as in the teaching UI's protocol; a scenario
    /// file nests the controller's under `[control]`).
    pub field: &'static str,
    /// Smallest accepted value.
    pub min: f64,
    /// Largest accepted value.
    pub max: f64,
    /// Unit, for messages and labels.
    pub unit: &'static str,
}

impl Limit {
    /// Whether `v` is finite and within `min..=max`.
    #[must_use]
    pub fn contains(&self, v: f64) -> bool {
        v.is_finite() && v >= self.min && v <= self.max
    }
}

impl core::fmt::Display for Limit {
    /// `[min, max] unit`, numbers in the shortest form that reads back.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "[{:e}, {:e}] {}", self.min, self.max, self.unit)
    }
}

const fn limit(field: &'static str, min: f64, max: f64, unit: &'static str) -> Limit {
    Limit {
        field,
        min,
        max,
        unit,
    }
}

/// `Q11 = var(e_d)`, m^2 per filter step.
pub const Q11: Limit = limit("q11", 1e-16, 10.0, "m^2 per step");
/// `Q22 = var(e_dtheta)`, rad^2 per filter step.
pub const Q22: Limit = limit("q22", 1e-16, 1e5, "rad^2 per step");
/// `R11 = var(e_ds1)`, m^2.
pub const R11: Limit = limit("r11", 1e-12, 1.0, "m^2");
/// `R22 = var(e_ds2)`, m^2.
pub const R22: Limit = limit("r22", 1e-12, 1.0, "m^2");
/// Standard deviation of the IR distance noise a simulator injects, m
/// (0: noise-free readings). At most 0.1 m: the paper's "variance 0.01"
/// read as m^2 (the spec assumes 2 cm), a third of the sensor's 30 cm
/// range; wider noise puts most readings outside the useful 4-30 cm.
pub const IR_SIGMA: Limit = limit("ir_sigma", 0.0, 0.1, "m");
/// Confidence of the chi-square gate on the NIS; 0 stands for no gate
/// (`None`), any other value must also be > 0.
pub const GATE: Limit = limit("gate", 0.0, 0.999_999, "(0 = no gate)");
/// The path controller's reference speed `V_ref`, m/s.
pub const V_REF: Limit = limit("v_ref", 0.01, 0.5, "m/s");
/// The path controller's reference turn rate `W_ref`, rad/s.
pub const W_REF: Limit = limit("w_ref", 0.05, 5.0, "rad/s");
/// The path controller's cross-track gain, rad/m.
pub const K_CROSS: Limit = limit("k_cross", 0.01, 100.0, "rad/m");
/// The path controller's heading gain, 1/s.
pub const K_HEADING: Limit = limit("k_heading", 0.01, 50.0, "1/s");
/// The path controller's position gain, 1/s.
pub const K_POS: Limit = limit("k_pos", 0.01, 20.0, "1/s");
/// Initial estimate's `x`, m (inside the square arena's walls at +-1 m).
pub const START_X: Limit = limit("start_x", -0.95, 0.95, "m");
/// Initial estimate's `y`, m.
pub const START_Y: Limit = limit("start_y", -0.95, 0.95, "m");
/// Initial estimate's heading, rad.
pub const START_THETA: Limit = limit("start_theta", -4.0, 4.0, "rad");
/// Standard deviation of the initial estimate's `x`, m (from 1e-12: a
/// test's start known exactly).
pub const STD_X: Limit = limit("std_x", 1e-12, 0.5, "m");
/// Standard deviation of the initial estimate's `y`, m.
pub const STD_Y: Limit = limit("std_y", 1e-12, 0.5, "m");
/// Standard deviation of the initial estimate's heading, rad.
pub const STD_THETA: Limit = limit("std_theta", 1e-12, 1.0, "rad");

/// The settings that may change while a loop runs (the filter's noise,
/// the gate, the injected IR noise, the controller).
pub const LIVE: [Limit; 11] = [
    Q11, Q22, R11, R22, IR_SIGMA, GATE, V_REF, W_REF, K_CROSS, K_HEADING, K_POS,
];

/// The initial belief: start pose and standard deviations.
pub const INITIAL: [Limit; 6] = [START_X, START_Y, START_THETA, STD_X, STD_Y, STD_THETA];

/// The limit of the setting named `field`, if it is one of [`LIVE`] or
/// [`INITIAL`].
#[must_use]
pub fn find(field: &str) -> Option<&'static Limit> {
    LIVE.iter().chain(INITIAL.iter()).find(|l| l.field == field)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_ordered_and_names_unique() {
        let all: [&Limit; 17] = core::array::from_fn(|i| {
            if i < LIVE.len() {
                &LIVE[i]
            } else {
                &INITIAL[i - LIVE.len()]
            }
        });
        for (i, l) in all.iter().enumerate() {
            assert!(
                l.min.is_finite() && l.max.is_finite() && l.min < l.max,
                "{}",
                l.field
            );
            assert!(all[..i].iter().all(|o| o.field != l.field), "{}", l.field);
            assert_eq!(find(l.field), Some(*l));
        }
        assert!(IR_SIGMA.contains(0.1) && !IR_SIGMA.contains(0.11));
        assert!(!Q11.contains(f64::NAN) && !Q11.contains(0.0));
    }
}
