//! The tables the commands print: one style for all ([`with_header`]), the
//! figures in them ([`fig`]: `n/a` for a figure that cannot be computed),
//! the summary of a single run, shared by `locus run` and `locus replay`
//! ([`summary`]), and tables of the results schema
//! ([`locus_eval::results`]): the estimators' honesty ([`honesty`]) and
//! the calibration ([`calibration`]); and the replay's settings as its
//! policy settled them ([`settings`]).

use comfy_table::{Row, Table, presets::UTF8_FULL};
use locus_eval::Summary;
use locus_eval::results::{Calibration, MeanStd, Results};
use locus_replay::policy::{Settled, Source as From};

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
        fig(s.position_rmse, 100.0, 2),
        fig(s.heading_rmse, deg, 2),
        fig(s.max_position_error, 100.0, 2),
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

/// Accuracy and honesty of the filter (and the smoother, if one ran):
/// RMSE, and the share of steps whose error lies inside the estimator's own
/// 3 sigma, and the mean NEES; "n/a" where nothing was compared.
#[must_use]
pub fn honesty(results: &Results) -> Table {
    let mut t = with_header([
        "estimate",
        "position RMSE [m]",
        "heading RMSE [rad]",
        "heading RMSE about its offset [rad]",
        "heading offset [rad]",
        "inside 3 sigma x / y / theta [%] (theta about the offset)",
        "mean NEES [-] (its dof if honest; about the offset)",
    ]);
    let rows = core::iter::once(("filter", results.filter))
        .chain(results.smoother.map(|s| ("smoother", s)));
    for (name, a) in rows {
        // With nothing compared every figure is "n/a", whatever it holds.
        let v = |x: f64| if a.compared == 0 { f64::NAN } else { x };
        let shares = [
            a.within_3_sigma_x_share,
            a.within_3_sigma_y_share,
            a.within_3_sigma_heading_share,
        ]
        .map(|s| fig(v(s), 100.0, 1))
        .join(" / ");
        t.add_row(vec![
            name.to_string(),
            // Four decimals: a millimetre matters on a rail or in a room.
            fig(v(a.position_rmse_m), 1.0, 4),
            fig(v(a.heading_rmse_rad), 1.0, 3),
            fig(v(a.heading_rmse_about_offset_rad), 1.0, 3),
            fig(v(a.heading_offset_rad), 1.0, 3),
            format!(
                "{shares} ({})",
                fig(v(a.within_3_sigma_heading_about_offset_share), 100.0, 1)
            ),
            format!(
                "{} ({} dof; {})",
                fig(v(a.mean_nees), 1.0, 2),
                a.nees_dof,
                fig(v(a.mean_nees_about_offset), 1.0, 2)
            ),
        ]);
    }
    t
}

/// The calibration the filter estimated (at its end) and, if given, the
/// smoother's (from the whole log): each term's mean +- its standard
/// deviation.
#[must_use]
pub fn calibration(filter: &Calibration, smoother: Option<&Calibration>) -> Table {
    fn terms(c: &Calibration) -> [MeanStd; 4] {
        [
            c.speed_scale,
            c.turn_rate_scale,
            c.turn_rate_bias_rad_per_s,
            c.bearing_bias_rad,
        ]
    }
    let names = [
        "forward-speed scale [-]",
        "turn-rate scale [-]",
        "turn-rate bias [rad/s]",
        "bearing bias [rad]",
    ];
    let pm = |m: MeanStd| format!("{:.4} +- {:.4}", m.mean, m.std);
    let mut t = with_header(["calibration [unit]", "filter (end)", "smoother (whole log)"]);
    let smoothed = smoother.map(terms);
    for (i, (name, term)) in names.iter().zip(terms(filter)).enumerate() {
        t.add_row(vec![
            (*name).to_string(),
            pm(term),
            smoothed.map_or_else(|| "-".to_string(), |s| pm(s[i])),
        ]);
    }
    t
}

/// The noise and odometry delay replayed with, where each came from (flag,
/// the log's record, the estimate, the default) and, for an estimate, its
/// standard error and the level the log itself shows; the biases held or
/// estimated.
#[must_use]
pub fn settings(settled: &Settled) -> Table {
    let mut t = with_header([
        "setting [unit]",
        "value",
        "+- (1 sigma)",
        "level the log shows (x widening)",
        "from",
    ]);
    for s in &settled.settings {
        let decimals = if s.name == "odometry_delay" { 2 } else { 5 };
        t.add_row(vec![
            format!("{} [{}]", s.name, s.unit),
            format!("{:.decimals$}", s.value),
            if s.source == From::Estimated {
                fig(s.se, 1.0, decimals)
            } else {
                "-".to_string()
            },
            if s.level == s.value {
                "-".to_string()
            } else {
                format!("{:.decimals$} (x{:.2})", s.level, s.value / s.level)
            },
            s.source.to_string(),
        ]);
    }
    if let Some(e) = &settled.estimate {
        t.add_row(vec![
            "process noise raised after the gaps [x]".to_string(),
            format!("{}", e.gap_factor),
            "-".to_string(),
            "-".to_string(),
            format!(
                "the median NIS of the sightings after gaps of {} s or more against \
                 chi-square's (1: honest already, or fewer than {} such sightings)",
                locus_replay::noise::GAP,
                locus_replay::noise::MIN_POST_GAP
            ),
        ]);
    }
    for b in &settled.biases {
        let (m, sd) = b.smoothed;
        let (value, from) = if b.held {
            (
                "held at 0".to_string(),
                format!(
                    "the log cannot tell it: the whole log gives {m:.4} +- {sd:.4}, over {} of \
                     the prior's {}",
                    locus_replay::policy::HOLD_RATIO,
                    b.prior_std
                ),
            )
        } else {
            (
                format!("estimated from 0 +- {}", b.prior_std),
                format!("the whole log tells it: {m:.4} +- {sd:.4}"),
            )
        };
        let name = format!("{} [{}]", b.name, b.unit);
        t.add_row(vec![name, value, "-".to_string(), "-".to_string(), from]);
    }
    if let Some(r) = &settled.range_bias {
        let threshold = locus_replay::noise::LR_HALF;
        let from = match (r.source, r.search) {
            (From::Given, _) => "given".to_string(),
            (_, Some(s)) if r.held => format!(
                "held at 0: white beams explain the log better (maximum likelihood, {} \
                 replays; the best bias found raises the innovation NLL by {:.1})",
                s.evaluations,
                s.nll - s.white_nll
            ),
            (_, Some(s)) => format!(
                "estimated from the log (maximum likelihood, {} replays): it lowers the \
                 innovation NLL by {:.1} against white beams searched alike ({} at 99 % beyond \
                 {threshold:.1})",
                s.evaluations,
                s.white_nll - s.nll,
                if s.significant() {
                    "significant"
                } else {
                    "not significant"
                }
            ),
            (_, None) => "held: sigma_beam is not estimated (given or in the log)".to_string(),
        };
        let (sigma, tau) = if r.held {
            ("held at 0".to_string(), "-".to_string())
        } else {
            (format!("{:.5}", r.bias.sigma), format!("{:.2}", r.bias.tau))
        };
        let dash = || "-".to_string();
        t.add_row(vec![
            "beam range bias sigma [m]".to_string(),
            sigma,
            dash(),
            dash(),
            from,
        ]);
        t.add_row(vec![
            "beam range bias tau [s]".to_string(),
            tau,
            dash(),
            dash(),
            dash(),
        ]);
    }
    t
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
