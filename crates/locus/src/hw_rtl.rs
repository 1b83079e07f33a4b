//! `locus hw`'s side of the Verilog core (`hdl/`): the test vectors it
//! exports from the Rust models (binary32 units, random corrections, the
//! corrections of a `wall45` run) and the Icarus simulation of the core
//! whose cycles it prints beside the model's.

use std::path::Path;

use anyhow::{Context, Result, bail};
use locus_hw::hdl::ekf_core::{self, CoreSim};
use locus_hw::hdl::fp32::{self, Op};
use locus_hw::{self as hw, CoreInputs, HwConfig, Schedule};

use crate::table::with_header;
use locus_sim::wall45::{Wall45Config, run_wall45};

/// Seed of the exported random vectors and of the `wall45` run.
pub const SEED: u64 = 1;

/// The core's inputs of every correction of a default `wall45` run with
/// the paper's laser model (`seed`), rounded to `f32` as the processor
/// writes them into the core's bank.
///
/// # Errors
/// A simulator error of the run.
#[allow(clippy::cast_possible_truncation)]
pub fn wall45_inputs(seed: u64) -> Result<Vec<CoreInputs>> {
    let mut out = Vec::new();
    run_wall45(&Wall45Config::default(), seed, &mut |r| {
        if let Some(c) = r.laser {
            out.push(CoreInputs {
                x: c.prior.x.map(|v| v as f32),
                p: c.prior.p.map(|v| v as f32),
                h: c.h.map(|v| v as f32),
                r: c.r.map(|v| v as f32),
                z: c.z.map(|v| v as f32),
                hx: c.hx.map(|v| v as f32),
            });
        }
    })?;
    Ok(out)
}

/// What [`export`] wrote.
#[derive(Debug, Clone, Copy)]
pub struct Exported {
    /// Vectors per binary32 unit (add, sub, mul, div), special values
    /// included.
    pub unit_vectors: usize,
    /// Random corrections.
    pub random_corrections: usize,
    /// Corrections of the `wall45` run.
    pub wall45_corrections: usize,
}

/// The most random operand pairs per unit [`export`] writes: each is a
/// line of about 30 bytes, and a unit's vectors are held in memory.
pub const MAX_UNIT_VECTORS: usize = 10_000_000;
/// The most random corrections [`export`] writes: each is a line of about
/// 500 bytes, and the corrections are held in memory.
pub const MAX_CORE_VECTORS: usize = 1_000_000;

/// Writes the test vectors to `dir`: `add.txt`, `sub.txt`, `mul.txt`,
/// `div.txt` (every pair of special values, then `units` random operand
/// pairs from the seed [`SEED`]), `core_random.txt` (`corrections` random
/// corrections) and `core_wall45.txt`, with the expected results of the
/// Rust models (`cfg`: the units' latencies).
///
/// The files are written into a staging folder beside `dir` and moved
/// into `dir` only once all are complete, so a failed export leaves no
/// partly written `dir`.
///
/// # Errors
/// A count above [`MAX_UNIT_VECTORS`] or [`MAX_CORE_VECTORS`]; the
/// directory or a file cannot be written; a model error.
pub fn export(dir: &Path, units: usize, corrections: usize, cfg: &HwConfig) -> Result<Exported> {
    if units > MAX_UNIT_VECTORS {
        bail!("--unit-vectors {units}: at most {MAX_UNIT_VECTORS}");
    }
    if corrections > MAX_CORE_VECTORS {
        bail!("--core-vectors {corrections}: at most {MAX_CORE_VECTORS}");
    }
    let name = dir
        .file_name()
        .with_context(|| format!("{}: not a folder name", dir.display()))?;
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    let staging = parent.join(format!(
        ".{}.partial-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&staging);
    std::fs::create_dir(&staging).with_context(|| format!("creating {}", staging.display()))?;
    let written = write_all(&staging, units, corrections, cfg).and_then(|e| {
        publish(&staging, dir)?;
        Ok(e)
    });
    let _ = std::fs::remove_dir_all(&staging);
    written
}

/// Moves the files of `staging` into `dir` (renaming `staging` itself
/// when `dir` does not exist yet).
fn publish(staging: &Path, dir: &Path) -> Result<()> {
    if !dir.exists() {
        return std::fs::rename(staging, dir)
            .with_context(|| format!("moving {} to {}", staging.display(), dir.display()));
    }
    for entry in std::fs::read_dir(staging)? {
        let from = entry?.path();
        let to = dir.join(from.file_name().unwrap_or_default());
        std::fs::rename(&from, &to)
            .with_context(|| format!("moving {} to {}", from.display(), to.display()))?;
    }
    Ok(())
}

/// [`export`]'s files, written into `dir`.
fn write_all(dir: &Path, units: usize, corrections: usize, cfg: &HwConfig) -> Result<Exported> {
    let mut unit_vectors = 0;
    for (i, op) in [Op::Add, Op::Sub, Op::Mul, Op::Div].into_iter().enumerate() {
        let mut vectors = fp32::special_vectors(op);
        vectors.extend(fp32::random_vectors(op, units, SEED + i as u64));
        let name = match op {
            Op::Add => "add",
            Op::Sub => "sub",
            Op::Mul => "mul",
            Op::Div => "div",
        };
        fp32::write_vectors(&dir.join(format!("{name}.txt")), &vectors)?;
        unit_vectors = vectors.len();
    }
    let random = ekf_core::random_inputs(corrections, SEED);
    ekf_core::write_vectors(&dir.join("core_random.txt"), cfg, &random)?;
    let wall45 = wall45_inputs(SEED)?;
    ekf_core::write_vectors(&dir.join("core_wall45.txt"), cfg, &wall45)?;
    Ok(Exported {
        unit_vectors,
        random_corrections: random.len(),
        wall45_corrections: wall45.len(),
    })
}

/// Prints the Verilog core's simulated cycles and time on `inputs` (Icarus
/// Verilog) beside the model's with the units' latencies and the paper's
/// 2.08 us; "n/a" with the reason when the simulator is missing.
///
/// # Errors
/// The latency header cannot be read; a model error.
#[allow(clippy::cast_precision_loss)]
pub fn print_simulated(inputs: &CoreInputs, clock_mhz: f64) -> Result<()> {
    let cfg = HwConfig {
        clock_hz: clock_mhz * 1e6,
        ..locus_hw::hdl::built_config()?
    };
    let latencies = cfg.latencies;
    let model = hw::run(&cfg, Schedule::Inverse2x2, inputs)?;
    let us = |cycles: u64| format!("{:.2}", cycles as f64 / clock_mhz);
    println!(
        "Verilog core (hdl/core/ekf_core.v), units built with latencies mult {} / add {} / div {} cycles, {} pipelined divider(s), +1 per state, {clock_mhz} MHz:",
        latencies.mul, latencies.add, latencies.div, cfg.dividers
    );
    let mut table = with_header([
        "",
        "cycles",
        "time [us]",
        "G, X+, P+ vs software f32 schedule",
    ]);
    match CoreSim::Icarus.run(&cfg, core::slice::from_ref(inputs)) {
        Ok(r) => table.add_row(vec![
            "simulated (Icarus Verilog)".to_owned(),
            r.cycles_max.to_string(),
            us(r.cycles_max),
            if r.mismatches == 0 {
                "bit-exact (18 of 18 words)".to_owned()
            } else {
                format!("{} of 18 words differ", r.mismatches)
            },
        ]),
        Err(e) => table.add_row(vec![
            "simulated (Icarus Verilog)".to_owned(),
            "n/a".to_owned(),
            "n/a".to_owned(),
            format!("n/a: {e}"),
        ]),
    };
    table.add_row(vec![
        "model, same latencies".to_owned(),
        model.cycles.to_string(),
        us(model.cycles),
        "-".to_owned(),
    ]);
    table.add_row(vec![
        "paper 003 (EP4CE115, 50 MHz)".to_owned(),
        "104".to_owned(),
        "2.08".to_owned(),
        "-".to_owned(),
    ]);
    println!("{table}");
    Ok(())
}
