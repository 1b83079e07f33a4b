//! `locus reproduce table3`: Table III of paper 000 (spec section 2) beside
//! Locus's Monte Carlo of the `wall45` scenario (`locus_sim::wall45`), with
//! the paper's `H` and with the exact laser model: per instant, the mean
//! estimate, the position and heading RMSE and the mean NEES over the seeds.
//!
//! The paper's figures are one run with unknown noise; Locus's are means
//! over many seeds with the spec's \[assumed\] noise. Compare in shape (how
//! the errors grow, what each model claims), not digit by digit. Units as
//! the paper: cm and degrees (NEES dimensionless).

use anyhow::{Context, Result, bail};
use clap::Args;
use locus_sim::wall45::{InstantStats, PAPER_TABLE3, Wall45Config, Wall45Noise, table3};

use crate::output::progress_bar;
use crate::run::seeds;
use crate::table::with_header;

/// What `locus reproduce` can reproduce.
pub const TARGETS: [&str; 1] = ["table3"];

/// Arguments of `locus reproduce`.
#[derive(Args, Debug)]
pub struct ReproduceArgs {
    /// What to reproduce: `table3` (paper 000's Table III).
    #[arg(default_value = "table3")]
    pub target: String,
    /// Monte Carlo runs per laser model [count, >= 100].
    #[arg(long, default_value_t = 200, value_parser = clap::value_parser!(u64).range(100..=1_000_000))]
    pub runs: u64,
    /// First seed; the runs use SEED..SEED+RUNS-1.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Simulate noise exactly as the filters assume (`wall45` ideal
    /// variant) instead of the realistic default.
    #[arg(long)]
    pub ideal: bool,
}

/// `x` (m) in cm, two decimals.
fn cm(x: f64) -> String {
    format!("{:.2}", 100.0 * x)
}

/// `x` (rad) in degrees, two decimals.
fn deg(x: f64) -> String {
    format!("{:.2}", x.to_degrees())
}

/// A row of the table: the instant (empty but on an instant's first row),
/// the source and six cells.
fn row(instant: String, source: &str, cells: [String; 6]) -> Vec<String> {
    let mut row = vec![instant, source.to_string()];
    row.extend(cells);
    row
}

/// One model's rows: mean estimate (cm, cm, deg), position RMSE (cm),
/// heading RMSE (deg), mean NEES.
fn model_cells(s: &InstantStats) -> [String; 6] {
    [
        cm(s.estimate[0]),
        cm(s.estimate[1]),
        deg(s.estimate[2]),
        cm(s.position_rmse),
        deg(s.heading_rmse),
        format!("{:.2}", s.mean_nees),
    ]
}

/// Runs `locus reproduce` and prints the table.
///
/// # Errors
/// An unknown target, a seed range overflowing `u64`, or a failed run.
pub fn run(args: &ReproduceArgs) -> Result<()> {
    if args.target != "table3" {
        bail!(
            "unknown reproduction target {:?}; known: {}",
            args.target,
            TARGETS.join(", ")
        );
    }
    let seeds = seeds(args.seed, args.runs)?;
    let cfg = Wall45Config {
        noise: if args.ideal {
            Wall45Noise::Ideal
        } else {
            Wall45Noise::Realistic
        },
        ..Wall45Config::default()
    };
    let bar = progress_bar(
        2 * args.runs,
        "{pos}/{len} runs, {elapsed} elapsed, eta {eta}",
    )?;
    let t = table3(&cfg, seeds.clone(), &|| bar.inc(1)).context("wall45 Monte Carlo")?;
    bar.finish_and_clear();

    println!(
        "locus reproduce table3: paper 000, skid-steer robot and laser at the wall x + y = {:.2} m; \
         Locus: {} noise, {} runs per model (seeds {}..={}), dT = {} s, {} s at rest per instant",
        cfg.wall_a,
        if args.ideal { "ideal" } else { "realistic" },
        t.runs,
        seeds.start,
        seeds.end - 1,
        cfg.dt,
        cfg.dwell
    );
    println!(
        "paper: one run, its EKF estimate; Locus: mean estimate, RMSE and mean NEES (3 dof, 3 if consistent) over the runs"
    );
    let mut table = with_header([
        "instant",
        "source",
        "x [cm]",
        "y [cm]",
        "theta [deg]",
        "pos RMSE [cm]",
        "heading RMSE [deg]",
        "mean NEES",
    ]);
    for (i, p) in PAPER_TABLE3.iter().enumerate() {
        let real = &t.paper_h[i].truth;
        let f2 = |v: f64| format!("{v:.2}");
        let blank = String::new;
        table.add_row(row(
            (i + 1).to_string(),
            "paper: real",
            [f2(p[0]), f2(p[1]), f2(p[2]), blank(), blank(), blank()],
        ));
        let paper_errors = [(p[3] - p[0]).hypot(p[4] - p[1]), (p[5] - p[2]).abs()];
        table.add_row(row(
            blank(),
            "paper: EKF",
            [
                f2(p[3]),
                f2(p[4]),
                f2(p[5]),
                f2(paper_errors[0]),
                f2(paper_errors[1]),
                blank(),
            ],
        ));
        table.add_row(row(
            blank(),
            "Locus: true (mean)",
            [
                cm(real[0]),
                cm(real[1]),
                deg(real[2]),
                blank(),
                blank(),
                blank(),
            ],
        ));
        for (name, s) in [
            ("Locus: paper H", &t.paper_h[i]),
            ("Locus: exact", &t.exact[i]),
        ] {
            table.add_row(row(blank(), name, model_cells(s)));
        }
        let o = &t.exact[i];
        table.add_row(row(
            blank(),
            "Locus: odometry",
            [
                blank(),
                blank(),
                blank(),
                cm(o.odometry_position_rmse),
                deg(o.odometry_heading_rmse),
                blank(),
            ],
        ));
    }
    println!("{table}");
    println!(
        "paper rows: the error columns are that single run's |error|. The paper's H holds the hit point \
         fixed and claims information along the wall a range cannot give: its NEES shows it."
    );
    Ok(())
}
