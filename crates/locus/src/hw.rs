//! `locus hw`: the cycle-level model of papers 000/003's FPGA correction core
//! (`locus_hw`) on one correction of paper 000's laser model:
//! cycles and time per correction beside the paper's 2.08 us, the operators
//! the schedule needs beside the paper's 9 adders, 9 multipliers and 4
//! dividers, cycles per FSM state, and a table over 1..9 datapaths for the
//! 2x2-inverse schedule and for scalar updates.

use anyhow::{Result, anyhow};
use clap::ValueEnum;
use locus_core::nalgebra::{Matrix3, Vector3};
use locus_core::{Belief, CovarianceUpdate, Ekf, MeasurementModel};
use locus_hw::{self as hw, CoreInputs, CoreRun, HwConfig, Latencies, Schedule};
use locus_models::{LaserMount, LaserWallPaper, WallLine};

use crate::table::with_header;

/// The paper's measured time of the core alone (seed 003, Table 3), s.
const PAPER_TIME_S: f64 = 2.08e-6;

/// Operator latency presets (Intel/Altera single-precision ALTFP cores).
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Preset {
    /// Fastest configurations: mult 5, add/sub 7, div 6 cycles.
    Fastest,
    /// Slowest (highest Fmax) configurations: mult 11, add/sub 14, div 33.
    Slowest,
}

/// Arguments of `locus hw`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Latency preset; `--mul`, `--add`, `--div`, `--transition` override it.
    #[arg(long, value_enum, default_value = "fastest")]
    pub preset: Preset,
    /// Multiplier latency (cycles).
    #[arg(long)]
    pub mul: Option<u64>,
    /// Adder/subtractor latency (cycles).
    #[arg(long)]
    pub add: Option<u64>,
    /// Divider latency (cycles).
    #[arg(long)]
    pub div: Option<u64>,
    /// Cycles per FSM state visit (state register and bank write).
    #[arg(long)]
    pub transition: Option<u64>,
    /// Parallel datapaths (the papers' core: 9).
    #[arg(long, default_value_t = 9)]
    pub datapaths: usize,
    /// Datapaths carrying a divider (the papers' core: 4).
    #[arg(long, default_value_t = 4)]
    pub dividers: usize,
    /// Clock (MHz; the papers' timings are at 50 MHz).
    #[arg(long, default_value_t = 50.0, value_parser = crate::args::positive_f64)]
    pub clock_mhz: f64,
    /// Write the test vectors of the Verilog core and units (hdl/) to DIR
    /// and exit: add.txt, sub.txt, mul.txt, div.txt (special-value pairs,
    /// then random operand pairs, with Rust's f32 results), core_random.txt
    /// and core_wall45.txt (the input bank and the software schedule's G,
    /// X+, P+ per correction).
    #[arg(long, value_name = "DIR")]
    pub export_vectors: Option<std::path::PathBuf>,
    /// Random operand pairs per unit in the exported vectors, at most
    /// 10000000 (about 300 MB per unit's file, held in memory while it is
    /// written).
    #[arg(
        long,
        default_value_t = 1_000_000,
        requires = "export_vectors",
        value_parser = |t: &str| crate::args::count_at_most(t, crate::hw_rtl::MAX_UNIT_VECTORS)
    )]
    pub unit_vectors: usize,
    /// Random corrections in core_random.txt, at most 1000000 (about
    /// 500 MB of file, held in memory while it is written).
    #[arg(
        long,
        default_value_t = 10_000,
        requires = "export_vectors",
        value_parser = |t: &str| crate::args::count_at_most(t, crate::hw_rtl::MAX_CORE_VECTORS)
    )]
    pub core_vectors: usize,
    /// Do not simulate the Verilog core (needs Icarus Verilog, `iverilog`).
    #[arg(long)]
    pub no_sim: bool,
    /// The output directory of a place-and-route run of the core
    /// (`bash scripts/hw_pnr.sh DIR`, default DIR target/hw-pnr): its
    /// Fmax, LUT4, flip-flops and multipliers beside the papers' core.
    /// Without it the row reads "n/a".
    #[arg(long, value_name = "DIR")]
    pub pnr: Option<std::path::PathBuf>,
}

/// Paper 000's laser-to-wall model (n = 3, m = 2) in f32.
fn model() -> LaserWallPaper<f32> {
    LaserWallPaper::new(
        LaserMount::<f32>::paper_000(),
        WallLine::paper_000(1.17f32),
        1e-4,
        1e-4,
    )
}

/// One correction of the [`model`], the core's input bank, with the
/// software plain-form result.
fn example() -> Result<(CoreInputs, Belief<f32, 3>)> {
    let model = model();
    let x = Vector3::new(0.02f32, -0.01, 0.03);
    let p = Matrix3::new(
        0.010f32, 0.002, 0.001, 0.002, 0.012, -0.001, 0.001, -0.001, 0.004,
    );
    let prior = Belief::new(x, p);
    let z = model.z_from_range(0.99f32);
    let hx = model
        .h(&x)
        .ok_or_else(|| anyhow!("the laser misses the wall"))?;
    let inputs = CoreInputs {
        x,
        p,
        h: model.jacobian(&x),
        r: model.noise(&x),
        z,
        hx,
    };
    let sw = Ekf::<f32>::new(CovarianceUpdate::Plain)
        .correct(&prior, &model, &z)?
        .belief;
    Ok((inputs, sw))
}

fn rel_diff(core: &CoreRun, sw: &Belief<f32, 3>, x0: &Vector3<f32>) -> (f32, f32) {
    let dx = ((core.x_post - x0) - (sw.x - x0)).amax() / (sw.x - x0).amax();
    let dp = (core.p_post - sw.p).amax() / sw.p.amax();
    (dx, dp)
}

/// Runs `locus hw`.
pub fn run(args: &Args) -> Result<()> {
    let base = match args.preset {
        Preset::Fastest => Latencies::ALTFP_FASTEST,
        Preset::Slowest => Latencies::ALTFP_SLOWEST,
    };
    let latencies = Latencies {
        mul: args.mul.unwrap_or(base.mul),
        add: args.add.unwrap_or(base.add),
        div: args.div.unwrap_or(base.div),
        transition: args.transition.unwrap_or(base.transition),
    };
    let cfg = HwConfig {
        latencies,
        datapaths: args.datapaths,
        dividers: args.dividers,
        clock_hz: args.clock_mhz * 1e6,
        ..HwConfig::default()
    };
    cfg.validate()?;
    if let Some(dir) = &args.export_vectors {
        let built = HwConfig {
            clock_hz: cfg.clock_hz,
            ..locus_hw::hdl::built_config()?
        };
        let e = crate::hw_rtl::export(dir, args.unit_vectors, args.core_vectors, &built)?;
        println!(
            "locus hw: wrote {} vectors per binary32 unit (add, sub, mul, div), {} random corrections and {} corrections of a wall45 run to {}",
            e.unit_vectors,
            e.random_corrections,
            e.wall45_corrections,
            dir.display()
        );
        return Ok(());
    }
    let (inputs, sw) = example()?;
    println!(
        "locus hw: correction core of papers 000/003, {} datapaths ({} with a divider), {} MHz, latencies mult {} / add {} / div {} cycles, +{} per state",
        cfg.datapaths,
        cfg.datapaths.min(cfg.dividers),
        args.clock_mhz,
        latencies.mul,
        latencies.add,
        latencies.div,
        latencies.transition
    );
    let mut table = with_header([
        "schedule",
        "cycles",
        "time [us]",
        "paper [us]",
        "model / paper",
        "multipliers / adders / dividers needed",
        "mul / add / div executed",
        "f32 vs software f32 (x, P rel.)",
    ]);
    for (name, schedule) in [
        ("11 steps, 2x2 inverse", Schedule::Inverse2x2),
        ("scalar updates", Schedule::Scalar),
    ] {
        let r = hw::run(&cfg, schedule, &inputs)?;
        let sw_ref = if schedule == Schedule::Scalar {
            // The sequential software correction for the scalar schedule.
            Ekf::<f32>::new(CovarianceUpdate::Plain)
                .correct_sequential(&Belief::new(inputs.x, inputs.p), &model(), &inputs.z)?
                .belief
        } else {
            sw
        };
        let (dx, dp) = rel_diff(&r, &sw_ref, &inputs.x);
        table.add_row(vec![
            name.to_owned(),
            r.cycles.to_string(),
            format!("{:.2}", r.time_s * 1e6),
            if schedule == Schedule::Inverse2x2 {
                format!("{:.2}", PAPER_TIME_S * 1e6)
            } else {
                "-".into()
            },
            if schedule == Schedule::Inverse2x2 {
                format!("{:.2}", r.time_s / PAPER_TIME_S)
            } else {
                "-".into()
            },
            format!(
                "{} / {} / {} (paper 9 / 9 / 4)",
                r.operators.mul, r.operators.add, r.operators.div
            ),
            format!(
                "{} / {} / {}",
                r.operations.mul, r.operations.add, r.operations.div
            ),
            format!("{dx:.1e}, {dp:.1e}"),
        ]);
    }
    println!("{table}");

    let r = hw::run(&cfg, Schedule::Inverse2x2, &inputs)?;
    let mut states = with_header(["state (11-step schedule)", "cycles", "share [%]"]);
    for (s, c) in r.cycles_per_state() {
        states.add_row(vec![
            s.name().to_owned(),
            c.to_string(),
            format!("{:.1}", 100.0 * c as f64 / r.cycles as f64),
        ]);
    }
    println!("{states}");

    let mut steps = with_header(["step", "cycles"]);
    let mut order: Vec<&'static str> = Vec::new();
    for p in &r.trace {
        if !order.contains(&p.step) {
            order.push(p.step);
        }
    }
    for s in order {
        let c: u64 = r
            .trace
            .iter()
            .filter(|p| p.step == s)
            .map(|p| p.cycles)
            .sum();
        steps.add_row(vec![s.to_owned(), c.to_string()]);
    }
    println!("{steps}");

    let mut sweep = with_header([
        "datapaths",
        "11-step cycles",
        "11-step [us]",
        "operators (mul/add/div)",
        "scalar cycles",
        "scalar [us]",
        "operators (mul/add/div)",
    ]);
    for d in 1..=9 {
        let c = HwConfig {
            datapaths: d,
            ..cfg
        };
        let a = hw::run(&c, Schedule::Inverse2x2, &inputs)?;
        let s = hw::run(&c, Schedule::Scalar, &inputs)?;
        sweep.add_row(vec![
            d.to_string(),
            a.cycles.to_string(),
            format!("{:.2}", a.time_s * 1e6),
            format!(
                "{}/{}/{}",
                a.operators.mul, a.operators.add, a.operators.div
            ),
            s.cycles.to_string(),
            format!("{:.2}", s.time_s * 1e6),
            format!(
                "{}/{}/{}",
                s.operators.mul, s.operators.add, s.operators.div
            ),
        ]);
    }
    println!("{sweep}");
    if !args.no_sim {
        crate::hw_rtl::print_simulated(&inputs, args.clock_mhz)?;
    }
    let built = locus_hw::hdl::built_config()?;
    let cycles = hw::run(&built, Schedule::Inverse2x2, &inputs)?.cycles;
    crate::hw_pnr::print(args.pnr.as_deref(), cycles)
}
