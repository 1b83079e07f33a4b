//! Scenarios by name or from a TOML file.
//!
//! A built-in scenario is a [`Scenario`] (`square`, `square-ideal`, `wall45`,
//! `tricycle-slip`, `hover`). A scenario file names its kind in a top-level `scenario = "square"` (any
//! built-in name); every other key overrides that built-in's configuration
//! (for `square`: the fields of [`SquareConfig`], nested `[control]` for the
//! controller). Unknown keys, wrong types and out-of-range values are
//! [`FileError::Invalid`] errors naming the file, line, column and field.
//! Every numeric field has a plausible range, stated in its error (each
//! kind's `validate`), and a run is at most [`MAX_STEPS`] steps; a file is
//! read up to [`MAX_FILE_BYTES`] ([`FileError::TooLarge`] otherwise).
//!
//! ```toml
//! scenario = "square"
//! laps = 1
//! q22 = 4e-6            # rad^2 per step
//! [control]
//! v_ref = 0.15          # m/s
//! ```
//!
//! Adding a scenario kind: a [`ScenarioConfig`] variant, a [`Scenario`]
//! (in [`Scenario::ALL`]) and one arm in each `match` of this file (the compiler lists
//! them: the enum is exhaustive). In [`parse`], a kind whose built-in is its
//! config's `Default` can use `toml::from_str::<XConfig>` on the blanked
//! text (needs only `Deserialize`); a preset that differs from `Default` uses `overlay` (also
//! `Serialize`, as does [`ScenarioConfig::to_toml`]).

use std::path::{Path, PathBuf};

use serde::Serialize;
use serde::de::DeserializeOwned;
use toml::de::{DeTable, DeValue};

use crate::closed_loop::{self, SquareConfig};
use crate::hover::HoverConfig;
use crate::tricycle_slip::TricycleSlipConfig;
use crate::wall45::Wall45Config;

/// Most steps of a run (`max_time / dt`, `duration / dt`, ...): a
/// configuration that would run longer is refused up front (the built-in
/// scenarios run 60 000 steps at most; 1e7 steps is a log of about 2 GB).
pub const MAX_STEPS: f64 = 1e7;

/// Largest scenario file read (bytes): a complete one is under 2 kB.
pub const MAX_FILE_BYTES: u64 = 1 << 20;

/// Whether `v` is finite and in `[lo, hi]` (the plausible ranges of the
/// configurations' fields).
pub(crate) fn within(v: f64, lo: f64, hi: f64) -> bool {
    v.is_finite() && (lo..=hi).contains(&v)
}

/// A built-in scenario. Its name (`square`, `square-ideal`, `wall45`,
/// `tricycle-slip`, `hover`) is what [`FromStr`](core::str::FromStr)
/// reads and [`Display`](core::fmt::Display) writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Scenario {
    /// Paper 001's closed loop on the square arena, realistic noise
    /// ([`SquareConfig::default`]).
    Square,
    /// The same loop with noise exactly as the filter assumes, no gate
    /// ([`SquareConfig::ideal`]).
    SquareIdeal,
    /// Paper 000's skid-steer robot at the 45-degree wall.
    Wall45,
    /// Paper 004's tricycle with wheel slip.
    TricycleSlip,
    /// Paper 002's body hovering in front of the camera.
    Hover,
}

impl Scenario {
    /// Every built-in scenario, in the order `--help` lists them.
    pub const ALL: [Self; 5] = [
        Self::Square,
        Self::SquareIdeal,
        Self::Wall45,
        Self::TricycleSlip,
        Self::Hover,
    ];

    /// The scenario's name (`square-ideal`).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::Square => "square",
            Self::SquareIdeal => "square-ideal",
            Self::Wall45 => "wall45",
            Self::TricycleSlip => "tricycle-slip",
            Self::Hover => "hover",
        }
    }

    /// What the scenario is, in one line (for `--help`).
    #[must_use]
    pub const fn summary(self) -> &'static str {
        match self {
            Self::Square => {
                "paper 001's differential-drive robot, two IR sensors, square arena; \
                 realistic noise (encoder quantisation, scale error, slip)"
            }
            Self::SquareIdeal => "the same loop with noise exactly as the filter's Q and R assume",
            Self::Wall45 => "paper 000's skid-steer robot, laser at the 45-degree wall",
            Self::TricycleSlip => {
                "paper 004's tricycle with wheel slip: rear-only against slip-rejecting odometry"
            }
            Self::Hover => "paper 002's body hovering before the camera (6-DOF pose from marks)",
        }
    }

    /// The scenario's configuration.
    #[must_use]
    pub fn config(self) -> ScenarioConfig {
        match self {
            Self::Square => ScenarioConfig::Square(SquareConfig::default()),
            Self::SquareIdeal => ScenarioConfig::Square(SquareConfig::ideal()),
            Self::Wall45 => ScenarioConfig::Wall45(Wall45Config::default()),
            Self::TricycleSlip => ScenarioConfig::TricycleSlip(TricycleSlipConfig::default()),
            Self::Hover => ScenarioConfig::Hover(HoverConfig::default()),
        }
    }

    /// The names of [`Scenario::ALL`], joined by `", "`.
    #[must_use]
    pub fn names() -> String {
        Self::ALL.map(Self::name).join(", ")
    }
}

impl core::fmt::Display for Scenario {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is no built-in scenario.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown scenario `{0}`; supported scenarios: {names}", names = Scenario::names())]
pub struct UnknownScenario(pub String);

impl core::str::FromStr for Scenario {
    type Err = UnknownScenario;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| UnknownScenario(s.to_string()))
    }
}

/// A scenario's configuration, by kind. Exhaustive on purpose: a new kind
/// must be handled wherever scenarios are dispatched.
#[derive(Debug, Clone, PartialEq)]
pub enum ScenarioConfig {
    /// Paper 001's closed loop on the square arena
    /// ([`crate::closed_loop::run_square`]).
    Square(SquareConfig),
    /// Paper 000's skid-steer robot with a laser at the 45-degree wall on
    /// Table III's path ([`crate::wall45::run_wall45`]).
    Wall45(Wall45Config),
    /// Paper 004's tricycle with wheel slip: rear-only against
    /// slip-rejecting odometry, and the EKF
    /// ([`crate::tricycle_slip::run_tricycle_slip`]).
    TricycleSlip(TricycleSlipConfig),
    /// Paper 002's body hovering in front of the camera with its marks
    /// ([`crate::hover::run_hover`]).
    Hover(HoverConfig),
}

impl ScenarioConfig {
    /// The kind's name in a scenario file (`square`).
    #[must_use]
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Square(_) => Scenario::Square,
            Self::Wall45(_) => Scenario::Wall45,
            Self::TricycleSlip(_) => Scenario::TricycleSlip,
            Self::Hover(_) => Scenario::Hover,
        }
        .name()
    }

    /// `Ok(())` if every value is in its domain.
    ///
    /// # Errors
    /// [`Invalid`]: the bad field (as named in a scenario file) if the
    /// kind's error names one, and the message.
    pub fn validate(&self) -> Result<(), Invalid> {
        let invalid = |e: closed_loop::Error| Invalid {
            field: match e {
                closed_loop::Error::Invalid { field, .. }
                | closed_loop::Error::OutOfRange { field, .. } => Some(field),
                _ => None,
            },
            message: e.to_string(),
        };
        match self {
            Self::Square(c) => c.validate().map_err(invalid),
            Self::Wall45(c) => c.validate().map_err(invalid),
            Self::TricycleSlip(c) => c.validate().map_err(invalid),
            Self::Hover(c) => c.validate().map_err(invalid),
        }
    }

    /// The configuration as a complete scenario file of kind `kind`: loading
    /// it gives this configuration back.
    ///
    /// # Errors
    /// [`FileError::Serialize`] if TOML cannot represent a value (a
    /// non-finite number).
    pub fn to_toml(&self, kind: &str) -> Result<String, FileError> {
        let body = match self {
            Self::Square(c) => toml::to_string(c),
            Self::Wall45(c) => toml::to_string(c),
            Self::TricycleSlip(c) => toml::to_string(c),
            Self::Hover(c) => toml::to_string(c),
        }
        .map_err(|e| FileError::Serialize(e.to_string()))?;
        Ok(format!(
            "# Locus scenario file (SI units: m, s, rad). Every key is optional and\n\
             # overrides the built-in `{kind}`; run it with `locus run FILE.toml`.\n\
             scenario = \"{kind}\"\n{body}"
        ))
    }
}

/// An out-of-range configuration value, kind-independent.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Invalid {
    /// The field as named in a scenario file (dotted for nested keys), if
    /// known.
    pub field: Option<&'static str>,
    /// What is wrong.
    pub message: String,
}

/// Errors of a scenario file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FileError {
    /// The file could not be read.
    #[error("cannot read scenario file {path}", path = .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is longer than [`MAX_FILE_BYTES`] (refused before it is
    /// parsed).
    #[error("{path}: scenario file larger than {max} bytes, the most read", path = .path.display())]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The limit (bytes).
        max: u64,
    },
    /// Bad TOML, a missing or unknown `scenario`, an unknown key, a wrong
    /// type or an out-of-range value.
    #[error("{path}{at}{field}: {message}",
        path = .path.display(),
        at = if *.line == 0 { String::new() } else { format!(", line {line}, column {column}") },
        field = .field.as_ref().map_or_else(String::new, |f| format!(", field `{f}`")))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Line of the offending text (1-based; 0 if the field is not in
        /// the file: its default value, or one derived from other fields).
        line: usize,
        /// Column of the offending text (1-based, in characters; 0 if
        /// unknown).
        column: usize,
        /// The key concerned (dotted path for nested keys), if known.
        field: Option<String>,
        /// What is wrong.
        message: String,
    },
    /// A configuration could not be written as TOML.
    #[error("cannot write the configuration as TOML: {0}")]
    Serialize(String),
}

/// Reads and parses the scenario file at `path` (at most
/// [`MAX_FILE_BYTES`], checked before it is read whole).
///
/// # Errors
/// [`FileError::Io`] if it cannot be read; [`FileError::TooLarge`];
/// [`FileError::Invalid`] as in [`parse`].
pub fn load(path: &Path) -> Result<ScenarioConfig, FileError> {
    use std::io::Read;
    let io = |source| FileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut text = String::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_FILE_BYTES + 1).read_to_string(&mut text))
        .map_err(io)?;
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(FileError::TooLarge {
            path: path.to_path_buf(),
            max: MAX_FILE_BYTES,
        });
    }
    parse(&text, path)
}

/// 1-based line and column (characters) of byte `offset` in `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// The dotted path of the key whose text or value holds byte `offset`
/// (innermost key of nested tables).
fn field_at(table: &DeTable<'_>, offset: usize) -> Option<String> {
    for (key, value) in table {
        let name = key.get_ref().to_string();
        if key.span().contains(&offset) {
            return Some(name);
        }
        // A `[table]`'s span may cover its header only: search its keys.
        if let DeValue::Table(inner) = value.get_ref() {
            if let Some(sub) = field_at(inner, offset) {
                return Some(format!("{name}.{sub}"));
            }
        }
        if value.span().contains(&offset) {
            return Some(name);
        }
    }
    None
}

/// Byte span of the key at dotted path `field` (its key text), if present.
fn key_span(table: &DeTable<'_>, field: &str) -> Option<core::ops::Range<usize>> {
    let (head, rest) = field.split_once('.').unwrap_or((field, ""));
    let (key, value) = table.iter().find(|(k, _)| k.get_ref() == head)?;
    if rest.is_empty() {
        return Some(key.span());
    }
    match value.get_ref() {
        DeValue::Table(inner) => key_span(inner, rest).or_else(|| Some(key.span())),
        _ => Some(key.span()),
    }
}

/// The overrides of `text` (the `scenario` key blanked) on top of `base`:
/// first checked against `C` alone, so unknown keys and wrong types report
/// their position, then merged key by key into `base`.
fn overlay<C>(base: &C, text: &str) -> Result<C, toml::de::Error>
where
    C: Serialize + DeserializeOwned,
{
    let _: C = toml::from_str(text)?;
    let user: toml::Table = toml::from_str(text)?;
    let mut merged = toml::Table::try_from(base).map_err(|e| {
        <toml::de::Error as serde::de::Error>::custom(format!("default configuration: {e}"))
    })?;
    merge(&mut merged, user);
    toml::Value::Table(merged).try_into()
}

/// The dotted key of `text` (a TOML table) that alone fails to
/// deserialize as `C`: where an error without a position (an array of the
/// wrong length, found only once the value is converted) comes from.
fn failing_key<C: DeserializeOwned>(text: &str) -> Option<String> {
    let user: toml::Table = toml::from_str(text).ok()?;
    let fails = |key: &str, value: toml::Value| {
        let mut one = toml::Table::new();
        one.insert(key.to_string(), value);
        toml::Value::Table(one).try_into::<C>().is_err()
    };
    for (key, value) in &user {
        if let toml::Value::Table(inner) = value {
            for (sub, v) in inner {
                let mut t = toml::Table::new();
                t.insert(sub.clone(), v.clone());
                if fails(key, toml::Value::Table(t)) {
                    return Some(format!("{key}.{sub}"));
                }
            }
        }
        if fails(key, value.clone()) {
            return Some(key.clone());
        }
    }
    None
}

/// Deep merge: `over`'s keys replace `into`'s, tables merge recursively.
fn merge(into: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (into.get_mut(&k), v) {
            (Some(toml::Value::Table(a)), toml::Value::Table(b)) => merge(a, b),
            (_, v) => {
                into.insert(k, v);
            }
        }
    }
}

/// Parses scenario file `text` (`path` is for the messages).
///
/// # Errors
/// [`FileError::Invalid`]: TOML syntax, no or an unknown `scenario` kind,
/// unknown keys, wrong types, values out of range; with line, column and
/// field.
pub fn parse(text: &str, path: &Path) -> Result<ScenarioConfig, FileError> {
    let invalid =
        |span: Option<core::ops::Range<usize>>, field: Option<String>, message: String| {
            let (line, column) = span.map_or((0, 0), |s| line_column(text, s.start));
            FileError::Invalid {
                path: path.to_path_buf(),
                line,
                column,
                field,
                message,
            }
        };
    let doc = DeTable::parse(text)
        .map_err(|e| invalid(e.span(), None, e.message().trim().to_string()))?;
    let table = doc.get_ref();
    let Some((key, value)) = table.iter().find(|(k, _)| k.get_ref() == "scenario") else {
        return Err(invalid(
            Some(0..0),
            Some("scenario".into()),
            format!(
                "missing top-level `scenario = \"KIND\"`; kinds: {}",
                Scenario::names()
            ),
        ));
    };
    let kind = match value.get_ref() {
        DeValue::String(s) => s.to_string(),
        _ => {
            return Err(invalid(
                Some(value.span()),
                Some("scenario".into()),
                "must be a string".into(),
            ));
        }
    };
    let Ok(base) = kind.parse::<Scenario>().map(Scenario::config) else {
        return Err(invalid(
            Some(value.span()),
            Some("scenario".into()),
            format!("unknown kind `{kind}`; kinds: {}", Scenario::names()),
        ));
    };
    // Blank `scenario = "..."` (same length: positions stay right).
    let mut blanked = text.to_string();
    let span = key.span().start..value.span().end;
    let spaces = " ".repeat(span.len());
    blanked.replace_range(span, &spaces);

    // An error without a position is placed at the key that causes it.
    let de_error = |e: toml::de::Error, failing: fn(&str) -> Option<String>| {
        let message = e.message().trim().to_string();
        if let Some(span) = e.span() {
            let field = field_at(table, span.start);
            return invalid(Some(span), field, message);
        }
        let field = failing(&blanked);
        let span = field.as_deref().and_then(|f| key_span(table, f));
        invalid(span, field, message)
    };
    let config = match base {
        ScenarioConfig::Square(b) => ScenarioConfig::Square(
            overlay(&b, &blanked).map_err(|e| de_error(e, failing_key::<SquareConfig>))?,
        ),
        ScenarioConfig::Wall45(b) => ScenarioConfig::Wall45(
            overlay(&b, &blanked).map_err(|e| de_error(e, failing_key::<Wall45Config>))?,
        ),
        ScenarioConfig::TricycleSlip(b) => ScenarioConfig::TricycleSlip(
            overlay(&b, &blanked).map_err(|e| de_error(e, failing_key::<TricycleSlipConfig>))?,
        ),
        ScenarioConfig::Hover(b) => ScenarioConfig::Hover(
            overlay(&b, &blanked).map_err(|e| de_error(e, failing_key::<HoverConfig>))?,
        ),
    };
    if let Err(Invalid { field, message }) = config.validate() {
        let span = field.and_then(|f| key_span(table, f));
        return Err(invalid(span, field.map(str::to_string), message));
    }
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column_are_one_based() {
        assert_eq!(line_column("ab\ncd", 0), (1, 1));
        assert_eq!(line_column("ab\ncd", 4), (2, 2));
    }
}
