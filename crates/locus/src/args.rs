//! Value parsers of the commands' number flags, so that a bad value is a
//! usage error naming the flag before any work starts (clap reports
//! `invalid value 'X' for '--flag <F>': ...` and exits with code 2):
//! `--ellipse-sigma -1` used to be refused only after the whole run.

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
}
