//! The columns every per-step CSV of a simulated run shares
//! (`docs/results.md`): after each scenario's leading columns (step, time,
//! ...), the truth, the estimate and the estimate's covariance
//! ([`POSE`]), written the same way by every scenario ([`pose_fields`]);
//! then the scenario's own columns. Each name ends in its unit.

/// The truth, the estimate and the covariance's x/y/heading terms.
pub const POSE: [&str; 10] = [
    "true_x_m",
    "true_y_m",
    "true_theta_rad",
    "ekf_x_m",
    "ekf_y_m",
    "ekf_theta_rad",
    "var_x_m2",
    "var_y_m2",
    "var_theta_rad2",
    "cov_xy_m2",
];

/// A header of `N` columns: `lead`, then [`POSE`], then `rest`. Evaluated
/// in a constant, a wrong `N` fails to compile.
///
/// # Panics
/// When `N` is not `lead.len() + 10 + rest.len()`.
#[must_use]
pub const fn header<const N: usize>(
    lead: &[&'static str],
    rest: &[&'static str],
) -> [&'static str; N] {
    let mut out = [""; N];
    let mut n = 0;
    let mut part = 0;
    while part < 3 {
        let names: &[&'static str] = match part {
            0 => lead,
            1 => &POSE,
            _ => rest,
        };
        let mut i = 0;
        while i < names.len() {
            assert!(n < N, "more columns than N");
            out[n] = names[i];
            n += 1;
            i += 1;
        }
        part += 1;
    }
    assert!(n == N, "fewer columns than N");
    out
}

/// A value in metres or radians as the CSVs write it: 9 decimals.
#[must_use]
pub fn fixed(v: f64) -> String {
    format!("{v:.9}")
}

/// An optional value: [`fixed`], or empty when absent.
#[must_use]
pub fn optional(v: Option<f64>) -> String {
    v.map_or_else(String::new, fixed)
}

/// The [`POSE`] fields: the truth and the estimate (x, y in m, heading in
/// rad) with [`fixed`], the variances and the x-y covariance in scientific
/// notation (6 decimals).
#[must_use]
pub fn pose_fields(truth: [f64; 3], estimate: [f64; 3], cov: &[[f64; 3]; 3]) -> [String; 10] {
    let e = |v: f64| format!("{v:.6e}");
    [
        fixed(truth[0]),
        fixed(truth[1]),
        fixed(truth[2]),
        fixed(estimate[0]),
        fixed(estimate[1]),
        fixed(estimate[2]),
        e(cov[0][0]),
        e(cov[1][1]),
        e(cov[2][2]),
        e(cov[0][1]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_header_is_lead_pose_rest() {
        const H: [&str; 13] = header(&["step", "time_s"], &["nees"]);
        assert_eq!(H[..2], ["step", "time_s"]);
        assert_eq!(H[2..12], POSE);
        assert_eq!(H[12], "nees");
    }

    #[test]
    #[should_panic(expected = "fewer columns than N")]
    fn a_header_of_the_wrong_length_is_refused() {
        let _ = header::<14>(&["step", "time_s"], &["nees"]);
    }

    #[test]
    fn absent_values_are_empty_and_present_ones_have_9_decimals() {
        assert_eq!(optional(None), "");
        assert_eq!(optional(Some(0.5)), "0.500000000");
    }
}
