//! Validation of every value the page sends: each field is parsed from a
//! JSON number or the text of an input box, must be finite and in the
//! range of [`LIMITS`], and a bad one is an [`Invalid`] naming the field.
//! A message with a bad field changes nothing (the run keeps its last good
//! values).

use serde::Serialize;
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

/// The accepted range of a numeric field: `min..=max` in `unit`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Limit {
    /// The field's name.
    pub field: &'static str,
    /// Smallest accepted value.
    pub min: f64,
    /// Largest accepted value.
    pub max: f64,
    /// Unit, for messages and labels.
    pub unit: &'static str,
}

/// Every numeric field the page can set, with its range. Wide enough for
/// the guide's extremes (`Q` of 1e-14 in step d, `Q22` of 1e4 in step e),
/// narrow enough to keep the simulation meaningful.
pub const LIMITS: [Limit; 20] = [
    Limit {
        field: "q11",
        min: 1e-16,
        max: 10.0,
        unit: "m^2 per step",
    },
    Limit {
        field: "q22",
        min: 1e-16,
        max: 1e5,
        unit: "rad^2 per step",
    },
    Limit {
        field: "r11",
        min: 1e-12,
        max: 1.0,
        unit: "m^2",
    },
    Limit {
        field: "r22",
        min: 1e-12,
        max: 1.0,
        unit: "m^2",
    },
    Limit {
        field: "ir_sigma",
        min: 0.0,
        max: 0.1,
        unit: "m",
    },
    Limit {
        field: "gate",
        min: 0.0,
        max: 0.999_999,
        unit: "(0 = no gate)",
    },
    Limit {
        field: "v_ref",
        min: 0.01,
        max: 0.5,
        unit: "m/s",
    },
    Limit {
        field: "w_ref",
        min: 0.05,
        max: 5.0,
        unit: "rad/s",
    },
    Limit {
        field: "k_cross",
        min: 0.01,
        max: 100.0,
        unit: "rad/m",
    },
    Limit {
        field: "k_heading",
        min: 0.01,
        max: 50.0,
        unit: "1/s",
    },
    Limit {
        field: "k_pos",
        min: 0.01,
        max: 20.0,
        unit: "1/s",
    },
    Limit {
        field: "speed",
        min: 0.1,
        max: 20.0,
        unit: "x real time",
    },
    Limit {
        field: "start_x",
        min: -0.95,
        max: 0.95,
        unit: "m",
    },
    Limit {
        field: "start_y",
        min: -0.95,
        max: 0.95,
        unit: "m",
    },
    Limit {
        field: "start_theta",
        min: -4.0,
        max: 4.0,
        unit: "rad",
    },
    Limit {
        field: "std_x",
        min: 1e-6,
        max: 0.5,
        unit: "m",
    },
    Limit {
        field: "std_y",
        min: 1e-6,
        max: 0.5,
        unit: "m",
    },
    Limit {
        field: "std_theta",
        min: 1e-6,
        max: 1.0,
        unit: "rad",
    },
    Limit {
        field: "teleop_v",
        min: -0.3,
        max: 0.3,
        unit: "m/s",
    },
    Limit {
        field: "teleop_w",
        min: -3.0,
        max: 3.0,
        unit: "rad/s",
    },
];

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
