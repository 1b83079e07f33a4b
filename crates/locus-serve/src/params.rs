//! Validation of every value the page sends: each field is parsed from a
//! JSON number or the text of an input box, must be finite and in the
//! range of [`LIMITS`] (the settings' ranges are
//! [`locus_models::settings`]'s, shared with the simulator and the host),
//! and a bad one is an [`Invalid`] naming the field. The live parameters
//! and the initial belief arrive as patches ([`ParamPatch`],
//! [`InitialPatch`]) whose unknown keys are refused.
//! A message with a bad field changes nothing (the run keeps its last good
//! values).

use locus_sim::LiveParams;
use serde::{Deserialize, Deserializer, Serialize};
use serde_json::Value;

/// A value from the page refused: the field's name (as in the protocol and
/// the page's inputs) and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error, Serialize)]
#[error("`{field}` {reason}")]
pub struct Invalid {
    /// The field's name (`r11`, `speed`, `start_x`, ...).
    pub field: String,
    /// What the value must be (with its unit).
    pub reason: String,
}

impl Invalid {
    /// A refusal of `field` because of `reason`.
    pub fn new(field: &str, reason: impl Into<String>) -> Self {
        Self {
            field: field.to_string(),
            reason: reason.into(),
        }
    }
}

pub use locus_models::settings::Limit;

/// The speed factor (simulated over wall-clock time).
pub const SPEED: Limit = Limit {
    field: "speed",
    min: 0.1,
    max: 20.0,
    unit: "x real time",
};
/// Keyboard teleoperation's linear speed, m/s.
pub const TELEOP_V: Limit = Limit {
    field: "teleop_v",
    min: -0.3,
    max: 0.3,
    unit: "m/s",
};
/// Keyboard teleoperation's turn rate, rad/s.
pub const TELEOP_W: Limit = Limit {
    field: "teleop_w",
    min: -3.0,
    max: 3.0,
    unit: "rad/s",
};

/// Every numeric field the page can set, with its range (sent to the page
/// in `hello`): the settings of [`locus_models::settings`], which the
/// simulator and the host check too, then the page's own (speed factor,
/// teleoperation).
pub const LIMITS: [Limit; 20] = {
    use locus_models::settings as s;
    [
        s::Q11,
        s::Q22,
        s::R11,
        s::R22,
        s::IR_SIGMA,
        s::GATE,
        s::V_REF,
        s::W_REF,
        s::K_CROSS,
        s::K_HEADING,
        s::K_POS,
        SPEED,
        s::START_X,
        s::START_Y,
        s::START_THETA,
        s::STD_X,
        s::STD_Y,
        s::STD_THETA,
        TELEOP_V,
        TELEOP_W,
    ]
};

/// The limit of `field` (one of [`LIMITS`]).
fn limit(field: &str) -> Option<&'static Limit> {
    LIMITS.iter().find(|l| l.field == field)
}

/// `value` as a number: a JSON number, or a string holding one (the text of
/// an input box, trimmed).
///
/// # Errors
/// [`Invalid`] if it is neither.
pub fn number(field: &str, value: &Value) -> Result<f64, Invalid> {
    match value {
        Value::Number(n) => n
            .as_f64()
            .ok_or_else(|| Invalid::new(field, "must be a number")),
        Value::String(s) => s
            .trim()
            .parse::<f64>()
            .map_err(|_| Invalid::new(field, format!("must be a number, not {:?}", clip(s)))),
        _ => Err(Invalid::new(field, "must be a number")),
    }
}

/// `s` cut to 40 characters for an error message.
fn clip(s: &str) -> String {
    s.chars().take(40).collect()
}

/// `value` checked as `field`: finite and within its [`Limit`].
///
/// # Errors
/// [`Invalid`] naming the field, with its range and unit.
pub fn checked(field: &str, value: &Value) -> Result<f64, Invalid> {
    let v = number(field, value)?;
    check(field, v)
}

/// `v` checked as `field`: finite and within its [`Limit`].
///
/// # Errors
/// [`Invalid`] naming the field, with its range and unit.
pub fn check(field: &str, v: f64) -> Result<f64, Invalid> {
    let Some(l) = limit(field) else {
        return Err(Invalid::new(field, "is not a known parameter"));
    };
    if !v.is_finite() {
        return Err(Invalid::new(field, "must be finite"));
    }
    if v < l.min || v > l.max {
        return Err(Invalid::new(
            field,
            format!(
                "must be in [{:e}, {:e}] {}, got {v:e}",
                l.min, l.max, l.unit
            ),
        ));
    }
    Ok(v)
}

/// `value` as a boolean (JSON `true`/`false` or the strings `"true"`,
/// `"false"`).
///
/// # Errors
/// [`Invalid`] otherwise.
pub fn boolean(field: &str, value: &Value) -> Result<bool, Invalid> {
    match value {
        Value::Bool(b) => Ok(*b),
        Value::String(s) if s == "true" => Ok(true),
        Value::String(s) if s == "false" => Ok(false),
        _ => Err(Invalid::new(field, "must be true or false")),
    }
}

/// A field of a patch as sent: `Some` whenever the key is present (JSON
/// `null` included, refused by the check, not taken for "absent").
#[allow(clippy::unnecessary_wraps)]
fn present<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Value>, D::Error> {
    Value::deserialize(d).map(Some)
}

/// The live parameters as the page sends them (the `params` message's
/// `values`), in the simulation and when attached to a robot alike: each
/// field optional, a number or its text (`use_ir`: a boolean or its text).
/// A key that is not a field is refused when the message is read
/// (`unknown field `KEY``), before anything is applied.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamPatch {
    /// `Q11` (m^2 per step).
    #[serde(default, deserialize_with = "present")]
    pub q11: Option<Value>,
    /// `Q22` (rad^2 per step).
    #[serde(default, deserialize_with = "present")]
    pub q22: Option<Value>,
    /// `R11` (m^2).
    #[serde(default, deserialize_with = "present")]
    pub r11: Option<Value>,
    /// `R22` (m^2).
    #[serde(default, deserialize_with = "present")]
    pub r22: Option<Value>,
    /// Injected IR noise (m; the simulation's only).
    #[serde(default, deserialize_with = "present")]
    pub ir_sigma: Option<Value>,
    /// Whether the filter uses the IR readings.
    #[serde(default, deserialize_with = "present")]
    pub use_ir: Option<Value>,
    /// Gate confidence (0: no gate).
    #[serde(default, deserialize_with = "present")]
    pub gate: Option<Value>,
    /// `V_ref` (m/s).
    #[serde(default, deserialize_with = "present")]
    pub v_ref: Option<Value>,
    /// `W_ref` (rad/s).
    #[serde(default, deserialize_with = "present")]
    pub w_ref: Option<Value>,
    /// Cross-track gain (rad/m).
    #[serde(default, deserialize_with = "present")]
    pub k_cross: Option<Value>,
    /// Heading gain (1/s).
    #[serde(default, deserialize_with = "present")]
    pub k_heading: Option<Value>,
    /// Position gain (1/s).
    #[serde(default, deserialize_with = "present")]
    pub k_pos: Option<Value>,
}

/// A [`ParamPatch`] checked: the fields given, each within its
/// [`LIMITS`] entry.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Settings {
    /// `Q11` (m^2 per step).
    pub q11: Option<f64>,
    /// `Q22` (rad^2 per step).
    pub q22: Option<f64>,
    /// `R11` (m^2).
    pub r11: Option<f64>,
    /// `R22` (m^2).
    pub r22: Option<f64>,
    /// Injected IR noise (m).
    pub ir_sigma: Option<f64>,
    /// Whether the filter uses the IR readings.
    pub use_ir: Option<bool>,
    /// Gate confidence (0: no gate).
    pub gate: Option<f64>,
    /// `V_ref` (m/s).
    pub v_ref: Option<f64>,
    /// `W_ref` (rad/s).
    pub w_ref: Option<f64>,
    /// Cross-track gain (rad/m).
    pub k_cross: Option<f64>,
    /// Heading gain (1/s).
    pub k_heading: Option<f64>,
    /// Position gain (1/s).
    pub k_pos: Option<f64>,
}

/// `value`, if given, checked against `limit`.
fn given(limit: &Limit, value: Option<&Value>) -> Result<Option<f64>, Invalid> {
    value.map(|v| checked(limit.field, v)).transpose()
}

impl ParamPatch {
    /// Every field given, checked against its limit; all or nothing.
    ///
    /// # Errors
    /// [`Invalid`] naming the first bad field.
    pub fn checked(&self) -> Result<Settings, Invalid> {
        use locus_models::settings as s;
        Ok(Settings {
            q11: given(&s::Q11, self.q11.as_ref())?,
            q22: given(&s::Q22, self.q22.as_ref())?,
            r11: given(&s::R11, self.r11.as_ref())?,
            r22: given(&s::R22, self.r22.as_ref())?,
            ir_sigma: given(&s::IR_SIGMA, self.ir_sigma.as_ref())?,
            use_ir: self
                .use_ir
                .as_ref()
                .map(|v| boolean("use_ir", v))
                .transpose()?,
            gate: given(&s::GATE, self.gate.as_ref())?,
            v_ref: given(&s::V_REF, self.v_ref.as_ref())?,
            w_ref: given(&s::W_REF, self.w_ref.as_ref())?,
            k_cross: given(&s::K_CROSS, self.k_cross.as_ref())?,
            k_heading: given(&s::K_HEADING, self.k_heading.as_ref())?,
            k_pos: given(&s::K_POS, self.k_pos.as_ref())?,
        })
    }
}

impl Settings {
    /// `live` with these settings (the fields not given kept; gate 0: no
    /// gate).
    #[must_use]
    pub fn applied_to(&self, live: &LiveParams) -> LiveParams {
        let c = live.control;
        LiveParams {
            q11: self.q11.unwrap_or(live.q11),
            q22: self.q22.unwrap_or(live.q22),
            r11: self.r11.unwrap_or(live.r11),
            r22: self.r22.unwrap_or(live.r22),
            ir_sigma: self.ir_sigma.unwrap_or(live.ir_sigma),
            use_ir: self.use_ir.unwrap_or(live.use_ir),
            gate_confidence: self
                .gate
                .map_or(live.gate_confidence, |g| (g > 0.0).then_some(g)),
            control: locus_control::Config {
                v_ref: self.v_ref.unwrap_or(c.v_ref),
                w_ref: self.w_ref.unwrap_or(c.w_ref),
                k_cross: self.k_cross.unwrap_or(c.k_cross),
                k_heading: self.k_heading.unwrap_or(c.k_heading),
                k_pos: self.k_pos.unwrap_or(c.k_pos),
                ..c
            },
        }
    }
}

/// The initial pose and standard deviations as the page sends them (the
/// `initial` message's `values`): each field optional, a number or its
/// text; an unknown key is refused when the message is read.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialPatch {
    /// Start `x` (m).
    #[serde(default, deserialize_with = "present")]
    pub start_x: Option<Value>,
    /// Start `y` (m).
    #[serde(default, deserialize_with = "present")]
    pub start_y: Option<Value>,
    /// Start heading (rad).
    #[serde(default, deserialize_with = "present")]
    pub start_theta: Option<Value>,
    /// Standard deviation of `x` (m).
    #[serde(default, deserialize_with = "present")]
    pub std_x: Option<Value>,
    /// Standard deviation of `y` (m).
    #[serde(default, deserialize_with = "present")]
    pub std_y: Option<Value>,
    /// Standard deviation of the heading (rad).
    #[serde(default, deserialize_with = "present")]
    pub std_theta: Option<Value>,
}

impl InitialPatch {
    /// `(start, std)` with the fields given replaced, each checked against
    /// its limit; all or nothing.
    ///
    /// # Errors
    /// [`Invalid`] naming the first bad field.
    pub fn applied_to(
        &self,
        start: [f64; 3],
        std: [f64; 3],
    ) -> Result<([f64; 3], [f64; 3]), Invalid> {
        use locus_models::settings as s;
        let pick =
            |limit: &Limit, v: Option<&Value>, old: f64| given(limit, v).map(|v| v.unwrap_or(old));
        Ok((
            [
                pick(&s::START_X, self.start_x.as_ref(), start[0])?,
                pick(&s::START_Y, self.start_y.as_ref(), start[1])?,
                pick(&s::START_THETA, self.start_theta.as_ref(), start[2])?,
            ],
            [
                pick(&s::STD_X, self.std_x.as_ref(), std[0])?,
                pick(&s::STD_Y, self.std_y.as_ref(), std[1])?,
                pick(&s::STD_THETA, self.std_theta.as_ref(), std[2])?,
            ],
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn numbers_from_json_and_text() {
        assert_eq!(checked("r11", &json!(1e-4)), Ok(1e-4));
        assert_eq!(checked("r11", &json!(" 2.5e-5 ")), Ok(2.5e-5));
    }

    #[test]
    fn refusals_name_the_field() {
        for (field, value, part) in [
            ("r11", json!("abc"), "must be a number"),
            ("r11", json!("1e999"), "must be finite"),
            ("r11", json!("NaN"), "must be finite"),
            ("r11", json!(-1.0), "must be in"),
            ("r11", json!(0.0), "must be in"),
            ("speed", json!(1000), "must be in"),
            ("q11", json!(null), "must be a number"),
            ("q11", json!([1]), "must be a number"),
            ("nope", json!(1), "not a known parameter"),
        ] {
            let e = checked(field, &value).unwrap_err();
            assert_eq!(e.field, field);
            assert!(e.reason.contains(part), "{field}={value}: {}", e.reason);
        }
    }

    #[test]
    fn an_unknown_key_is_refused_naming_it() {
        for key in ["q12", "ir_noise", "start_x", "speed"] {
            let e = serde_json::from_value::<ParamPatch>(json!({"r11": 1e-4, key: 1})).unwrap_err();
            assert!(
                e.to_string().contains(&format!("unknown field `{key}`")),
                "{e}"
            );
        }
        let e = serde_json::from_value::<InitialPatch>(json!({"start_z": 0})).unwrap_err();
        assert!(e.to_string().contains("unknown field `start_z`"), "{e}");
    }

    /// One table: a value the page refuses, the simulator refuses too (and
    /// the other way round), with the field named.
    #[test]
    fn the_page_and_the_simulator_share_the_limits() {
        type Set = fn(&mut locus_sim::SquareConfig, f64);
        let cases: [(&str, &str, f64, f64, Set); 6] = [
            ("ir_sigma", "ir_sigma", 0.1, 0.2, |c, v| c.ir_sigma = v),
            ("v_ref", "control.v_ref", 0.5, 1.0, |c, v| {
                c.control.v_ref = v
            }),
            ("k_cross", "control.k_cross", 100.0, 200.0, |c, v| {
                c.control.k_cross = v;
            }),
            ("q22", "q22", 1e5, 2e5, |c, v| c.q22 = v),
            ("std_theta", "initial_std", 1.0, 2.0, |c, v| {
                c.initial_std[2] = v;
            }),
            ("start_x", "start", -0.95, -1.5, |c, v| c.start[0] = v),
        ];
        for (field, sim_field, inside, outside, set) in cases {
            let mut cfg = locus_sim::SquareConfig::default();
            set(&mut cfg, inside);
            assert_eq!(check(field, inside), Ok(inside), "{field}");
            assert_eq!(cfg.validate(), Ok(()), "{field} = {inside}");
            set(&mut cfg, outside);
            assert_eq!(check(field, outside).unwrap_err().field, field);
            match cfg.validate() {
                Err(locus_sim::Error::OutOfRange { field: f, .. }) => {
                    assert_eq!(f, sim_field, "{field}");
                }
                other => panic!("{field} = {outside}: {other:?}"),
            }
        }
        // Through the live path too.
        let patch: ParamPatch = serde_json::from_value(json!({"ir_sigma": 0.2})).unwrap();
        assert_eq!(patch.checked().unwrap_err().field, "ir_sigma");
    }

    #[test]
    fn every_default_is_within_its_limit() {
        let cfg = locus_sim::SquareConfig::default();
        let c = cfg.control;
        for (field, v) in [
            ("q11", cfg.q11),
            ("q22", cfg.q22),
            ("r11", cfg.r11),
            ("r22", cfg.r22),
            ("ir_sigma", cfg.ir_sigma),
            ("gate", cfg.gate_confidence.unwrap_or(0.0)),
            ("v_ref", c.v_ref),
            ("w_ref", c.w_ref),
            ("k_cross", c.k_cross),
            ("k_heading", c.k_heading),
            ("k_pos", c.k_pos),
            ("start_x", cfg.start[0]),
            ("start_y", cfg.start[1]),
            ("start_theta", cfg.start[2]),
            ("std_x", cfg.initial_std[0]),
            ("std_y", cfg.initial_std[1]),
            ("std_theta", cfg.initial_std[2]),
        ] {
            assert_eq!(check(field, v), Ok(v), "{field}");
        }
    }
}
