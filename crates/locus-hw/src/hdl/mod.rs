//! Hardware descriptions of the correction core's arithmetic and their
//! tests against Rust.
//!
//! The repository's `hdl/` directory (next to `crates/`) holds Verilog-2005:
//! * `hdl/fp/`: pipelined IEEE 754 binary32 units `fp_add` (with a `sub`
//!   input), `fp_mul` and `fp_div`, their shared functions `fp_common.vh`
//!   (unpack with subnormal normalisation, round to nearest even and pack
//!   with gradual underflow) and their latencies `fp_latency.vh` (add 3,
//!   mul 3, div 13 cycles; the multiplier and the divider register their operands first): `y` holds the result of the operands sampled at
//!   rising edge `t` from just after edge `t + L - 1`, one operation per
//!   clock);
//! * `hdl/tb/tb_fp.v`: one testbench for the three units, fed with a vector
//!   file (`+vectors=FILE +unit=add|mul|div`), which prints
//!   `vectors N mismatches M`.
//!
//! [`fp32`] has the software reference (Rust's `f32`, with the hardware's
//! NaN rule), the vector generator and the runner. The runner finds Icarus
//! Verilog's `iverilog` and `vvp` on `PATH` (Debian: `apt-get install
//! iverilog`), compiles the testbench and the units into a temporary
//! directory and runs the simulation there; the `hdl/` directory is found
//! from this crate's manifest directory ([`hdl_dir`]).

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::{HwConfig, Latencies};

pub mod ekf_core;
pub mod fp32;

/// An error of the HDL runner.
#[derive(Debug, thiserror::Error)]
pub enum HdlError {
    /// A simulator tool is not on `PATH`.
    #[error(
        "`{tool}` not found: install Debian's iverilog and verilator: apt-get install iverilog verilator"
    )]
    SimulatorMissing {
        /// The tool (`iverilog` or `vvp`).
        tool: &'static str,
    },
    /// A file or process operation failed.
    #[error("hdl: {context}: {source}")]
    Io {
        /// What was being done.
        context: String,
        /// The cause.
        source: std::io::Error,
    },
    /// `iverilog` rejected the sources.
    #[error("hdl: iverilog failed:\n{0}")]
    Compile(String),
    /// The simulation did not print its summary line.
    #[error("hdl: the simulation printed no summary line:\n{0}")]
    NoSummary(String),
    /// The software model refused an input of the vectors.
    #[error("hdl: the model refused a correction: {0}")]
    Model(#[from] crate::HwError),
}

impl HdlError {
    fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        Self::Io {
            context: context.into(),
            source,
        }
    }
}

/// Datapaths of the Verilog core: six, one per element of a 3x2 result
/// (the papers' core has nine); a 3x3 result's row 2 runs on datapaths 3-5
/// in the same wave ([`HwConfig::overlap`]).
pub const BUILT_DATAPATHS: usize = 6;

/// Dividers of the Verilog core: one, pipelined, shared by step 4's four
/// divisions (`hdl/core/ekf_core.v`; the papers' core has four).
pub const BUILT_DIVIDERS: usize = 1;

/// The cycle-level model's configuration of the Verilog core: its units'
/// latencies ([`built_latencies`]), its [`BUILT_DIVIDERS`] dividers, the
/// second product forwarded into the adder, steps 6-8 on operators other
/// steps leave idle and element-wise operands registered before the adder,
/// on [`BUILT_DATAPATHS`] datapaths at the papers' 50 MHz.
///
/// # Errors
/// Those of [`built_latencies`].
pub fn built_config() -> Result<HwConfig, HdlError> {
    Ok(HwConfig {
        latencies: built_latencies()?,
        dividers: BUILT_DIVIDERS,
        forward: true,
        overlap: true,
        elementwise_register: true,
        datapaths: BUILT_DATAPATHS,
        ..HwConfig::default()
    })
}

/// The cycle-level model of the Verilog core: the latencies the units are
/// built with (`hdl/fp/fp_latency.vh`) and one cycle per state visit (the
/// cycle whose end writes the bank).
///
/// # Errors
/// [`HdlError::Io`] if the header cannot be read;
/// [`HdlError::NoSummary`] if it lacks a latency.
pub fn built_latencies() -> Result<Latencies, HdlError> {
    let path = hdl_dir().join("fp/fp_latency.vh");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| HdlError::io(format!("reading {}", path.display()), e))?;
    let find = |name: &str| {
        text.lines().find_map(|l| {
            let mut w = l.split_whitespace();
            (w.next() == Some("`define") && w.next() == Some(name))
                .then(|| w.next()?.parse::<u64>().ok())
                .flatten()
        })
    };
    match (find("FP_MUL_LAT"), find("FP_ADD_LAT"), find("FP_DIV_LAT")) {
        (Some(mul), Some(add), Some(div)) => Ok(Latencies {
            mul,
            add,
            div,
            transition: 1,
        }),
        _ => Err(HdlError::NoSummary(format!(
            "{} does not define FP_MUL_LAT, FP_ADD_LAT and FP_DIV_LAT",
            path.display()
        ))),
    }
}

/// A temporary directory, removed on drop.
#[derive(Debug)]
pub struct TempDir(PathBuf);

impl TempDir {
    /// A new empty directory under the system's temporary directory,
    /// named after the process, a counter and `tag`.
    ///
    /// # Errors
    /// [`HdlError::Io`] if it cannot be created.
    pub fn new(tag: &str) -> Result<Self, HdlError> {
        use core::sync::atomic::{AtomicU32, Ordering};
        static NEXT: AtomicU32 = AtomicU32::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("locus-hdl-{}-{n}-{tag}", std::process::id()));
        std::fs::create_dir_all(&dir)
            .map_err(|e| HdlError::io(format!("creating {}", dir.display()), e))?;
        Ok(Self(dir))
    }

    /// The directory.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn spawn_error(tool: &'static str, source: std::io::Error) -> HdlError {
    if source.kind() == std::io::ErrorKind::NotFound {
        HdlError::SimulatorMissing { tool }
    } else {
        HdlError::io(format!("running {tool}"), source)
    }
}

/// A Verilog testbench compiled by Verilator (`--binary --timing`) into
/// a native simulator, for runs too long for Icarus: the core's 10^4
/// corrections take seconds instead of minutes.
#[derive(Debug)]
pub struct VerilatedSim {
    dir: TempDir,
}

impl VerilatedSim {
    /// Compiles `sources` (paths under [`hdl_dir`]) with `top` as the top
    /// module (about a minute for the core).
    ///
    /// # Errors
    /// [`HdlError::SimulatorMissing`] (Debian: `apt-get install
    /// verilator`), [`HdlError::Compile`] or [`HdlError::Io`].
    pub fn build(top: &str, sources: &[&str]) -> Result<Self, HdlError> {
        let hdl = hdl_dir();
        let dir = TempDir::new(top)?;
        let out = Command::new("verilator")
            .args([
                "--binary",
                "--timing",
                "-Wno-fatal",
                "-Wno-lint",
                "-Wno-style",
            ])
            .arg(format!("-I{}", hdl.join("fp").display()))
            .args(["--top-module", top, "-o", "sim", "-Mdir"])
            .arg(dir.path().join("obj"))
            .args(sources.iter().map(|f| hdl.join(f)))
            .output()
            .map_err(|e| spawn_error("verilator", e))?;
        if !out.status.success() {
            return Err(HdlError::Compile(format!(
                "{}{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            )));
        }
        Ok(Self { dir })
    }

    /// Runs the simulator with `plusargs`; returns what it printed.
    ///
    /// # Errors
    /// [`HdlError::Io`] if it cannot be started.
    pub fn run(&self, plusargs: &[String]) -> Result<String, HdlError> {
        let out = Command::new(self.dir.path().join("obj/sim"))
            .args(plusargs)
            .output()
            .map_err(|e| HdlError::io("running the verilated simulator", e))?;
        Ok(format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ))
    }
}

/// Compiles `sources` (paths under [`hdl_dir`]; the first is the
/// testbench, the top module) with `iverilog -g2005 -I hdl/fp` into `dir`
/// and runs it with `vvp` and `plusargs`; returns what it printed.
///
/// # Errors
/// [`HdlError::SimulatorMissing`], [`HdlError::Compile`] or
/// [`HdlError::Io`].
pub fn simulate(dir: &TempDir, sources: &[&str], plusargs: &[String]) -> Result<String, HdlError> {
    let hdl = hdl_dir();
    let sim = dir.path().join("sim.vvp");
    let out = Command::new("iverilog")
        .arg("-g2005")
        .arg("-I")
        .arg(hdl.join("fp"))
        .arg("-o")
        .arg(&sim)
        .args(sources.iter().map(|f| hdl.join(f)))
        .output()
        .map_err(|e| spawn_error("iverilog", e))?;
    if !out.status.success() {
        return Err(HdlError::Compile(
            String::from_utf8_lossy(&out.stderr).into_owned(),
        ));
    }
    let out = Command::new("vvp")
        .arg("-n")
        .arg(&sim)
        .args(plusargs)
        .output()
        .map_err(|e| spawn_error("vvp", e))?;
    Ok(format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    ))
}

/// The repository's `hdl/` directory (`../../hdl` from this crate).
pub fn hdl_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../hdl")
}
