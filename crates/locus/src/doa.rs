//! `locus doa`: the domain of attraction of paper 002's observer (spec
//! section 4) over a `(v_g, alpha)` grid, and `locus doa merge` to join
//! shards. Outputs `doa.csv` (or `doa-shard-I-of-N.csv`), heatmaps of
//! `M_zeta` and of the settling time (PNG and SVG, in the manner of the
//! paper's Fig. 4 and 5) and a summary table. The maths is in
//! `locus_doa`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Subcommand;
use locus_doa::{CellResult, DoaConfig, DoaResult, Shard, Study, merge_csv};
use plotters::prelude::*;

use crate::font::{self, FAMILY};
use crate::output::progress_bar;
use crate::plot::{err, on_backend};
use crate::table::with_header;

/// Arguments of `locus doa`.
#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Args {
    /// `merge`: join shard CSV files into the whole grid.
    #[command(subcommand)]
    pub command: Option<DoaCommand>,
    /// TOML configuration (grid, geometry, noise, run, search); every field
    /// is optional and defaults to the spec's values (12 v_g x 25 alpha).
    pub config: Option<PathBuf>,
    /// Compute only the deterministic slice I/N of the grid (0-based I): the
    /// cells whose row-major index c has c mod N = I. Join with `locus doa
    /// merge`.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Output directory.
    #[arg(long, default_value = "out/doa")]
    pub out: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Do not draw the heatmaps.
    #[arg(long)]
    pub no_plots: bool,
}

/// Subcommands of `locus doa`.
#[derive(Subcommand, Debug)]
pub enum DoaCommand {
    /// Join the CSV files of all shards of one study into `doa.csv`, and draw
    /// the heatmaps.
    Merge(MergeArgs),
}

/// Arguments of `locus doa merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// The shard files (`doa-shard-I-of-N.csv`), all N of them.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// The configuration the shards were computed with (for the axes' values
    /// the CSV already holds; used to check the configuration hash).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "out/doa")]
    pub out: PathBuf,
    /// Do not draw the heatmaps.
    #[arg(long)]
    pub no_plots: bool,
}

/// Runs `locus doa` or `locus doa merge`.
pub fn run(args: &Args) -> Result<()> {
    if let Some(DoaCommand::Merge(m)) = &args.command {
        return run_merge(m);
    }
    let config = load_config(args.config.as_deref())?;
    let shard = match &args.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::ALL,
    };
    let study = Study::new(config)?;
    // The output directory before the work: a bad `--out` must not cost
    // the whole computation.
    crate::output::writable_dir(&args.out)?;
    let cells = study.cells().filter(|c| shard.contains(c.index)).count();
    let g = &study.config().grid;
    println!(
        "locus doa: paper 002 domain of attraction, {} v_g x {} alpha grid, shard {shard}: {cells} cells, 64 vertices each, {} steps of {} s",
        g.v_g_count,
        g.alpha_count,
        study.config().run.steps(),
        study.config().run.dt
    );
    let bar = progress_bar(
        cells as u64,
        "{pos}/{len} cells, {elapsed} elapsed, eta {eta}",
    )?;
    let started = Instant::now();
    let pool = {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(t) = args.threads {
            b = b.num_threads(t);
        }
        b.build().context("building the thread pool")?
    };
    let result = pool.install(|| study.sweep(shard, &|_| bar.inc(1)));
    bar.finish_and_clear();
    let wall = started.elapsed().as_secs_f64();
    println!(
        "computed {cells} cells in {wall:.1} s wall time on {} threads",
        pool.current_num_threads()
    );
    let name = if shard.count > 1 {
        format!("doa-shard-{}-of-{}.csv", shard.index, shard.count)
    } else {
        "doa.csv".to_owned()
    };
    let csv = args.out.join(name);
    std::fs::write(&csv, result.to_csv()).with_context(|| format!("writing {}", csv.display()))?;
    println!("wrote {}", csv.display());
    if shard.count == 1 {
        report(&result, &args.out, args.no_plots)?;
    }
    Ok(())
}

fn load_config(path: Option<&Path>) -> Result<DoaConfig> {
    Ok(match path {
        Some(p) => DoaConfig::load(p)?,
        None => DoaConfig::default(),
    })
}

fn run_merge(args: &MergeArgs) -> Result<()> {
    // Everything checkable before the shards are read: the configuration
    // and the output directory.
    let config = args.config.as_deref().map(DoaConfig::load).transpose()?;
    crate::output::writable_dir(&args.out)?;
    let mut texts = Vec::with_capacity(args.inputs.len());
    for p in &args.inputs {
        let text = crate::output::read_bounded(p, MAX_SHARD_BYTES)?;
        texts.push((p.display().to_string(), text));
    }
    let config_name = args.config.as_ref().map(|c| c.display().to_string());
    let merged = merge_csv(
        texts.iter().map(|(n, t)| (n.as_str(), t.as_str())),
        config.as_ref().zip(config_name.as_deref()),
    )?;
    let csv = args.out.join("doa.csv");
    std::fs::write(&csv, merged.to_csv()).with_context(|| format!("writing {}", csv.display()))?;
    println!(
        "merged {} shards ({} cells) into {}",
        args.inputs.len(),
        merged.cells.len(),
        csv.display()
    );
    report(&merged, &args.out, args.no_plots)
}

/// Largest shard file read (bytes): a line per cell, under 200 bytes each,
/// for at most `MAX_GRID_CELLS` cells.
const MAX_SHARD_BYTES: u64 = 200 * locus_doa::MAX_GRID_CELLS as u64;

/// Axis values of a whole-grid result: (v_g by row, alpha by column).
fn axes(result: &DoaResult) -> (Vec<f64>, Vec<f64>) {
    let mut v_g = vec![f64::NAN; result.v_g_count];
    let mut alpha = vec![f64::NAN; result.alpha_count];
    for r in &result.cells {
        v_g[r.cell.i_vg] = r.cell.v_g;
        alpha[r.cell.i_alpha] = r.cell.alpha;
    }
    (v_g, alpha)
}

/// Prints the summary table and draws the heatmaps.
fn report(result: &DoaResult, out: &Path, no_plots: bool) -> Result<()> {
    let (v_g, alpha) = axes(result);
    let cols: Vec<usize> = {
        let mut c: Vec<usize> = [5.0, 25.0, 50.0, 75.0, 100.0, 125.0]
            .iter()
            .filter_map(|a| alpha.iter().position(|x| (x - a).abs() < 1e-9))
            .collect();
        if c.is_empty() {
            c = (0..alpha.len()).collect();
        }
        c
    };
    let mut header = vec!["v_g".to_owned()];
    header.extend(cols.iter().map(|&j| format!("M_zeta a={}", alpha[j])));
    header.push("max M_zeta (alpha)".into());
    header.push("settle [s] a=5 / 50 / 100".into());
    let mut table = with_header(header);
    for (i, vg) in v_g.iter().enumerate() {
        let mut row = vec![format!("{vg:.4}")];
        for &j in &cols {
            row.push(
                result
                    .get(i, j)
                    .map_or("-".into(), |r| format!("{:.2}", r.m_zeta)),
            );
        }
        let best = (0..alpha.len())
            .filter_map(|j| result.get(i, j))
            .max_by(|a, b| a.m_zeta.total_cmp(&b.m_zeta));
        row.push(best.map_or("-".into(), |r| {
            format!("{:.2} ({})", r.m_zeta, r.cell.alpha)
        }));
        let settle = |a: f64| {
            alpha
                .iter()
                .position(|x| (x - a).abs() < 1e-9)
                .and_then(|j| result.get(i, j))
                .map_or("-".to_owned(), |r| {
                    r.settle.map_or("n/c".into(), |s| format!("{s:.3}"))
                })
        };
        row.push(format!(
            "{} / {} / {}",
            settle(5.0),
            settle(50.0),
            settle(100.0)
        ));
        table.add_row(row);
    }
    println!(
        "M_zeta (m, rad) and worst settling time at m_zeta = settle amplitude (n/c: some vertex does not converge)"
    );
    println!("{table}");
    if no_plots {
        return Ok(());
    }
    // One figure per cell, `None` where the grid has no value.
    let grid = |value: &dyn Fn(&CellResult) -> Option<f64>| -> Vec<Vec<Option<f64>>> {
        (0..v_g.len())
            .map(|i| {
                (0..alpha.len())
                    .map(|j| result.get(i, j).and_then(value))
                    .collect()
            })
            .collect()
    };
    let m = grid(&|r| Some(r.m_zeta));
    let s = grid(&|r| r.settle);
    font::register()?;
    for ext in ["png", "svg"] {
        for (name, title, values, decimals) in [
            (
                "doa_m_zeta",
                "Domain of attraction M_zeta (m, rad), paper 002 Fig. 4",
                &m,
                2,
            ),
            (
                "doa_settling_time",
                "Worst settling time (s) at m_zeta = 0.1, paper 002 Fig. 5 (blank: not converged)",
                &s,
                3,
            ),
        ] {
            let path = out.join(format!("{name}.{ext}"));
            on_backend!(
                ext,
                &path,
                HEATMAP_SIZE,
                draw_heatmap(title, values, &v_g, &alpha, decimals)
            )
            .with_context(|| format!("writing {}", path.display()))?;
        }
    }
    println!(
        "wrote {0}/doa_m_zeta.{{png,svg}} and {0}/doa_settling_time.{{png,svg}}",
        out.display()
    );
    Ok(())
}

/// A perceptually ordered colour map (viridis, 5 anchors, linear between).
fn viridis(t: f64) -> RGBColor {
    const A: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = t.clamp(0.0, 1.0) * 4.0;
    let k = (t.floor() as usize).min(3);
    let f = t - k as f64;
    let lerp = |a: f64, b: f64| (a + (b - a) * f).round() as u8;
    RGBColor(
        lerp(A[k].0, A[k + 1].0),
        lerp(A[k].1, A[k + 1].1),
        lerp(A[k].2, A[k + 1].2),
    )
}

/// Size of a heatmap picture (pixels).
const HEATMAP_SIZE: (u32, u32) = (1400, 760);

/// A heatmap of `values[i_vg][i_alpha]` (rows v_g upwards, columns alpha),
/// each cell labelled with its value.
fn draw_heatmap<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    values: &[Vec<Option<f64>>],
    v_g: &[f64],
    alpha: &[f64],
    decimals: usize,
) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let (nv, na) = (v_g.len(), alpha.len());
    let max = values
        .iter()
        .flatten()
        .flatten()
        .fold(0.0f64, |m, v| m.max(*v));
    let scale = if max > 0.0 { max } else { 1.0 };
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FAMILY, 22))
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(-0.5..na as f64 - 0.5, -0.5..nv as f64 - 0.5)
        .map_err(err)?;
    let (a2, v2) = (alpha.to_vec(), v_g.to_vec());
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("alpha (1/s)")
        .y_desc("v_g (P0 = v_g Q)")
        .x_labels(na.min(25))
        .y_labels(nv.min(25))
        // Cell k spans [k - 0.5, k + 0.5]: label the integer positions only.
        .x_label_formatter(&move |x| {
            let j = x.round();
            if (x - j).abs() > 1e-6 || j < 0.0 {
                return String::new();
            }
            a2.get(j as usize).map_or(String::new(), |a| format!("{a}"))
        })
        .y_label_formatter(&move |y| {
            let i = y.round();
            if (y - i).abs() > 1e-6 || i < 0.0 {
                return String::new();
            }
            v2.get(i as usize)
                .map_or(String::new(), |v| format!("{v:.4}"))
        })
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .draw()
        .map_err(err)?;
    for (i, row) in values.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            let (x0, y0) = (j as f64 - 0.5, i as f64 - 0.5);
            let colour = v.map_or(RGBColor(235, 235, 235), |v| viridis(v / scale));
            chart
                .draw_series(core::iter::once(Rectangle::new(
                    [(x0, y0), (x0 + 1.0, y0 + 1.0)],
                    colour.filled(),
                )))
                .map_err(err)?;
            if let Some(v) = v {
                let text_colour = if v / scale > 0.6 { &BLACK } else { &WHITE };
                chart
                    .draw_series(core::iter::once(Text::new(
                        format!("{v:.decimals$}"),
                        (x0 + 0.12, y0 + 0.65),
                        (FAMILY, 11).into_font().color(text_colour),
                    )))
                    .map_err(err)?;
            }
        }
    }
    root.present().map_err(err)?;
    Ok(())
}
