//! Value parsers of the commands' number flags, so that a bad value is a
//! usage error naming the flag before any work starts (clap reports
//! `invalid value 'X' for '--flag <F>': ...` and exits with code 2):
//! `--ellipse-sigma -1` used to be refused only after the whole run.
//! The scenario argument of `run`, `serve`, `robot` and `host`
//! ([`ScenarioArg`]) is parsed here too, and the replay's flags, which
//! `locus replay` parses and `locus tune` and `locus family` take the
//! defaults of ([`replay`]).

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use clap::builder::{PossibleValue, TypedValueParser};
use clap::error::ErrorKind;
use locus_sim::scenario_file::{self, Scenario, ScenarioConfig, UnknownScenario};

pub mod replay;

/// A finite number (not NaN, not infinite).
///
/// # Errors
/// The text is not a number, or not a finite one.
pub fn finite_f64(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("must be finite, got {v}"))
    }
}

/// A finite number `> 0`.
///
/// # Errors
/// As [`finite_f64`], or the number is `<= 0`.
pub fn positive_f64(text: &str) -> Result<f64, String> {
    let v = finite_f64(text)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be > 0, got {v}"))
    }
}

/// The slowest serial line speed `--baud` accepts, bits per second: the
/// lowest standard UART rate.
pub const MIN_BAUD: u32 = 50;
/// The fastest serial line speed `--baud` accepts, bits per second: the
/// top of what common USB-serial and SoC UARTs run (4 Mbaud).
pub const MAX_BAUD: u32 = 4_000_000;

/// A serial line speed in bits per second, [`MIN_BAUD`]..=[`MAX_BAUD`]:
/// speed 0 means "hang up" to a real serial line, and a rate beyond what
/// UARTs run would be rejected or silently rounded by the driver.
///
/// # Errors
/// The text is not a whole number, or it is outside the range.
pub fn baud(text: &str) -> Result<u32, String> {
    let range = format!("a UART speed in bits per second, {MIN_BAUD}..={MAX_BAUD}");
    let v: u64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not {range}"))?;
    u32::try_from(v)
        .ok()
        .filter(|b| (MIN_BAUD..=MAX_BAUD).contains(b))
        .ok_or_else(|| format!("{v} is outside {range}"))
}

/// A count of at most `max`.
///
/// # Errors
/// The text is not a whole number, or it is above `max`.
pub fn count_at_most(text: &str, max: usize) -> Result<usize, String> {
    let v: u128 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a whole number"))?;
    usize::try_from(v)
        .ok()
        .filter(|&n| n <= max)
        .ok_or_else(|| format!("{v} is too many: at most {max}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_finite_numbers_in_range_pass() {
        assert_eq!(positive_f64("3"), Ok(3.0));
        assert_eq!(finite_f64("-2.5"), Ok(-2.5));
        for bad in ["-1", "0", "NaN", "nan", "inf", "-inf", "1e999", "x", ""] {
            assert!(positive_f64(bad).is_err(), "{bad}");
        }
        assert!(finite_f64("NaN").is_err());
    }

    #[test]
    fn only_uart_speeds_pass() {
        assert_eq!(baud("115200"), Ok(115_200));
        assert_eq!(baud("50"), Ok(50));
        assert_eq!(baud("4000000"), Ok(4_000_000));
        for bad in ["0", "49", "4000001", "4000000000", "-9600", "9600.5", ""] {
            assert!(baud(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn counts_above_the_bound_are_refused() {
        assert_eq!(count_at_most("10", 10), Ok(10));
        assert!(count_at_most("11", 10).unwrap_err().contains("at most 10"));
        assert!(count_at_most("100000000000000000000000", 10).is_err());
        assert!(count_at_most("-1", 10).is_err());
    }
}

/// A scenario argument: a built-in [`Scenario`] by name, or a TOML
/// scenario file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ScenarioArg {
    /// A built-in scenario.
    Builtin(Scenario),
    /// A scenario file (`scenario = "KIND"` and overrides).
    File(PathBuf),
}

impl core::fmt::Display for ScenarioArg {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Builtin(s) => s.fmt(f),
            Self::File(p) => p.display().fmt(f),
        }
    }
}

impl ScenarioArg {
    /// The built-in scenario or the file's (loaded and checked)
    /// configuration.
    ///
    /// # Errors
    /// The file cannot be read or is not a valid scenario file.
    pub fn config(&self) -> anyhow::Result<ScenarioConfig> {
        match self {
            Self::Builtin(s) => Ok(s.config()),
            Self::File(p) => Ok(scenario_file::load(p)?),
        }
    }
}

/// The value parser of a `SCENARIO|FILE` argument: a built-in name
/// ([`Scenario`]'s, listed as the possible values in `--help`), or a path
/// that ends in `.toml` or names a file.
#[derive(Debug, Clone, Copy)]
pub struct ScenarioParser;

impl TypedValueParser for ScenarioParser {
    type Value = ScenarioArg;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<ScenarioArg, clap::Error> {
        let text = value.to_string_lossy();
        if let Ok(s) = text.parse::<Scenario>() {
            return Ok(ScenarioArg::Builtin(s));
        }
        let path = Path::new(value);
        if path.extension().is_some_and(|e| e == "toml") || path.is_file() {
            return Ok(ScenarioArg::File(path.to_path_buf()));
        }
        let what = arg.map_or_else(|| "SCENARIO".to_string(), ToString::to_string);
        Err(clap::Error::raw(
            ErrorKind::InvalidValue,
            format!(
                "{what}: {}, or a scenario file FILE.toml\n",
                UnknownScenario(text.into_owned())
            ),
        )
        .with_cmd(cmd))
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(
            Scenario::ALL
                .into_iter()
                .map(|s| PossibleValue::new(s.name()).help(s.summary())),
        ))
    }
}
