//! The tables the commands print: one style for all ([`with_header`]), the
//! figures in them ([`fig`]: `n/a` for a figure that cannot be computed)
//! and the summary of a single run, shared by `locus run` and
//! `locus replay` ([`summary`]).

use comfy_table::{Row, Table, presets::UTF8_FULL};
use locus_eval::Summary;

/// An empty table in the commands' style with the column names `header`.
pub fn with_header(header: impl Into<Row>) -> Table {
    let mut table = Table::new();
    table.load_preset(UTF8_FULL).set_header(header);
    table
}

/// A figure for a table: `scale * v` with `decimals`, or `n/a` when `v` is
/// not finite (e.g. odometry in a scenario without it, the min and max of
/// no values), as `metrics.json` writes it as `null`.
#[must_use]
pub fn fig(v: f64, scale: f64, decimals: usize) -> String {
    if !v.is_finite() {
        "n/a".to_string()
    } else {
        format!("{:.*}", decimals, scale * v)
    }
}

/// The two tables of a single run's summary: the estimators' errors and
/// the filter's checks; `estimator` labels the filter's row, `measurement`
/// names the measurements counted (e.g. `IR`, `landmark`).
#[must_use]
pub fn summary((estimator, measurement): (&str, &str), s: &Summary) -> String {
    let mut table = with_header([
        "estimator",
        "position RMSE [cm]",
        "heading RMSE [deg]",
        "max position error [cm]",
    ]);
    let deg = 180.0 / core::f64::consts::PI;
    table.add_row(vec![
        estimator.to_string(),
        fig(s.ekf_position_rmse, 100.0, 2),
        fig(s.ekf_heading_rmse, deg, 2),
        fig(s.ekf_max_position_error, 100.0, 2),
    ]);
    table.add_row(vec![
        "odometry alone".to_string(),
        fig(s.odometry_position_rmse, 100.0, 2),
        fig(s.odometry_heading_rmse, deg, 2),
        fig(s.odometry_max_position_error, 100.0, 2),
    ]);

    let mut filter = with_header(["filter check [unit]", "value"]);
    let dof = s.nees_dof;
    let rows = [
        (
            format!("mean NEES ({dof} dof, ideal {dof}) [-]"),
            fig(s.mean_nees, 1.0, 2),
        ),
        (
            format!("steps with NEES in 95 % chi-square({dof}) interval [%]"),
            fig(s.nees_in_interval, 100.0, 1),
        ),
        (
            format!("{measurement} readings / associated / applied [count]"),
            format!("{} / {} / {}", s.readings, s.associated, s.applied),
        ),
        (
            "updates accepted by the gate [%]".to_string(),
            fig(s.acceptance, 100.0, 1),
        ),
        (
            "real-time factor [x]".to_string(),
            fig(s.real_time_factor, 1.0, 0),
        ),
    ];
    for (name, value) in rows {
        filter.add_row(vec![name, value]);
    }
    format!("{table}\n{filter}\n")
}

#[cfg(test)]
mod tests {
    use super::fig;

    #[test]
    fn a_missing_figure_is_printed_as_n_a() {
        assert_eq!(fig(f64::NAN, 100.0, 2), "n/a");
        assert_eq!(fig(f64::INFINITY, 100.0, 2), "n/a");
        assert_eq!(fig(0.0117, 100.0, 2), "1.17");
    }
}
