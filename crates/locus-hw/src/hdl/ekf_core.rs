//! The correction core in Verilog (`hdl/core/ekf_core.v`) against the
//! software `f32` schedule ([`crate::run`]): test vectors, one
//! correction per line (the input bank and the expected `G`, `X+`, `P+`),
//! and the simulation of `hdl/tb/tb_core.v` over them (Icarus Verilog or,
//! for long runs, Verilator), which reports
//! mismatching words, the cycles from `start` to `done` and the cycles per
//! FSM state.

use core::fmt::Write as _;
use std::path::Path;

use locus_core::MeasurementModel;
use locus_core::nalgebra::{Matrix3, Vector3};
use locus_models::{LaserMount, LaserWallPaper, WallLine};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use super::{HdlError, TempDir, VerilatedSim};
use crate::{CoreInputs, CoreRun, HwConfig, Schedule, State};

/// Words per vector line: 26 inputs and 18 results.
pub const WORDS: usize = 44;

/// The input bank of one correction and the expected results, as the
/// testbench reads them: `X-` (3), `P-` (9, row-major), `H` (6), `R` (4),
/// `z` (2), `h(X-)` (2), then `G` (6), `X+` (3), `P+` (9), each a binary32
/// word in hexadecimal.
#[must_use]
pub fn vector_line(inp: &CoreInputs, run: &CoreRun) -> String {
    let mut words: Vec<f32> = Vec::with_capacity(WORDS);
    words.extend(inp.x.iter());
    words.extend(row_major(&inp.p));
    words.extend(row_major(&inp.h));
    words.extend(row_major(&inp.r));
    words.extend(inp.z.iter());
    words.extend(inp.hx.iter());
    words.extend(row_major(&run.gain));
    words.extend(run.x_post.iter());
    words.extend(row_major(&run.p_post));
    let mut line = String::with_capacity(WORDS * 9);
    for (i, w) in words.iter().enumerate() {
        if i > 0 {
            line.push(' ');
        }
        let _ = write!(line, "{:08x}", w.to_bits());
    }
    line
}

fn row_major<const R: usize, const C: usize>(
    m: &locus_core::nalgebra::SMatrix<f32, R, C>,
) -> impl Iterator<Item = f32> + '_ {
    (0..R).flat_map(move |i| (0..C).map(move |j| m[(i, j)]))
}

/// `n` corrections of realistic magnitude from `seed`: paper 000's laser
/// model on a wall 1.17 m away (n = 3, m = 2), a prior within 5 cm / 0.05
/// rad of the origin with a random positive-definite covariance (standard
/// deviations of a few cm), range noise variances around 1e-4 m^2 and
/// ranges within 2 cm of 1 m.
#[must_use]
pub fn random_inputs(n: usize, seed: u64) -> Vec<CoreInputs> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let mut u = || rng.random_range(-1.0f32..1.0);
        let model = LaserWallPaper::new(
            LaserMount::<f32>::paper_000(),
            WallLine::paper_000(1.17f32),
            1e-4 * (1.0 + 0.5 * u()),
            2e-4 * (1.0 + 0.5 * u()),
        );
        let x = Vector3::new(0.05 * u(), 0.05 * u(), 0.05 * u());
        let l = Matrix3::from_fn(|_, _| 0.05 * u());
        let p = l * l.transpose() + Matrix3::from_diagonal(&Vector3::new(1e-3, 1e-3, 2e-4));
        let z = model.z_from_range(1.0 + 0.02 * u());
        if let Some(hx) = model.h(&x) {
            out.push(CoreInputs {
                x,
                p,
                h: model.jacobian(&x),
                r: model.noise(&x),
                z,
                hx,
            });
        }
    }
    out
}

/// What the core's simulation reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoreSimReport {
    /// Corrections simulated.
    pub corrections: u64,
    /// Result words that differ from the software schedule's.
    pub mismatches: u64,
    /// Fewest cycles from `start` to `done`.
    pub cycles_min: u64,
    /// Most cycles from `start` to `done`.
    pub cycles_max: u64,
    /// Cycles per FSM state of the last correction, in the order of
    /// [`State`] (waiting, mult1, mult2, multadd, add, div1).
    pub states: [u64; 6],
}

impl CoreSimReport {
    /// The cycles per state as the model reports them
    /// ([`CoreRun::cycles_per_state`]).
    #[must_use]
    pub fn cycles_per_state(&self) -> [(State, u64); 6] {
        let s = self.states;
        [
            (State::Waiting, s[0]),
            (State::Mult1, s[1]),
            (State::Mult2, s[2]),
            (State::Multadd, s[3]),
            (State::Add, s[4]),
            (State::Div1, s[5]),
        ]
    }
}

/// Writes the vectors of `inputs` (expected results from the model with
/// `cfg`'s latencies, the 11-step schedule) to `path`.
///
/// # Errors
/// [`HdlError::Model`] if the model refuses an input (a singular `O3`, a
/// non-finite result); [`HdlError::Io`] if the file cannot be written.
pub fn write_vectors(path: &Path, cfg: &HwConfig, inputs: &[CoreInputs]) -> Result<(), HdlError> {
    let mut text = String::with_capacity(inputs.len() * WORDS * 9);
    for inp in inputs {
        let run = crate::run(cfg, Schedule::Inverse2x2, inp)?;
        text.push_str(&vector_line(inp, &run));
        text.push('\n');
    }
    std::fs::write(path, text).map_err(|e| HdlError::io(format!("writing {}", path.display()), e))
}

/// The core's testbench and sources, testbench first.
const SOURCES: [&str; 5] = [
    "tb/tb_core.v",
    "core/ekf_core.v",
    "fp/fp_add.v",
    "fp/fp_mul.v",
    "fp/fp_div.v",
];

/// Which simulator runs the core.
#[derive(Debug)]
pub enum CoreSim {
    /// Icarus Verilog (event-driven; slow on the core: about 15 corrections
    /// per second).
    Icarus,
    /// The core compiled by Verilator (thousands of corrections per second).
    Verilator(VerilatedSim),
}

impl CoreSim {
    /// The core compiled by Verilator.
    ///
    /// # Errors
    /// As [`VerilatedSim::build`].
    pub fn verilator() -> Result<Self, HdlError> {
        Ok(Self::Verilator(VerilatedSim::build("tb_core", &SOURCES)?))
    }

    /// Simulates the core over the vector file `vectors`.
    ///
    /// # Errors
    /// [`HdlError`] if the simulator is missing, fails, or prints no
    /// summary.
    pub fn run_file(&self, vectors: &Path) -> Result<CoreSimReport, HdlError> {
        let plusargs = [format!("+vectors={}", vectors.display())];
        let out = match self {
            Self::Icarus => {
                let dir = TempDir::new("core")?;
                super::simulate(&dir, &SOURCES, &plusargs)?
            }
            Self::Verilator(sim) => sim.run(&plusargs)?,
        };
        parse_summary(&out)
    }

    /// Simulates the core on `inputs`, the expected results from the
    /// model with `cfg` (a temporary vector file).
    ///
    /// # Errors
    /// As [`write_vectors`] and [`CoreSim::run_file`].
    pub fn run(&self, cfg: &HwConfig, inputs: &[CoreInputs]) -> Result<CoreSimReport, HdlError> {
        let dir = TempDir::new("core-vectors")?;
        let path = dir.path().join("core.txt");
        write_vectors(&path, cfg, inputs)?;
        self.run_file(&path)
    }
}

/// The summary line `corrections N mismatches M cycles MIN MAX states ...`.
fn parse_summary(out: &str) -> Result<CoreSimReport, HdlError> {
    let line = out
        .lines()
        .find(|l| l.starts_with("corrections "))
        .ok_or_else(|| HdlError::NoSummary(out.chars().take(2000).collect()))?;
    let n: Vec<u64> = line
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    if n.len() != 10 {
        return Err(HdlError::NoSummary(line.to_string()));
    }
    Ok(CoreSimReport {
        corrections: n[0],
        mismatches: n[1],
        cycles_min: n[2],
        cycles_max: n[3],
        states: [n[4], n[5], n[6], n[7], n[8], n[9]],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_summary_is_read_and_a_missing_one_is_an_error() {
        let r = parse_summary(
            "mismatch: ...\ncorrections 3 mismatches 1 cycles 99 99 states 2 21 14 33 20 9\n",
        )
        .unwrap();
        assert_eq!((r.corrections, r.mismatches, r.cycles_max), (3, 1, 99));
        assert_eq!(r.states, [2, 21, 14, 33, 20, 9]);
        assert!(parse_summary("error: cannot open x").is_err());
    }

    #[test]
    fn a_vector_line_has_the_bank_then_the_results() {
        let inp = random_inputs(1, 3)[0];
        let run = crate::run(&HwConfig::default(), Schedule::Inverse2x2, &inp).unwrap();
        let line = vector_line(&inp, &run);
        let words: Vec<&str> = line.split(' ').collect();
        assert_eq!(words.len(), WORDS);
        assert_eq!(words[0], format!("{:08x}", inp.x[0].to_bits()));
        assert_eq!(words[4], format!("{:08x}", inp.p[(0, 1)].to_bits()));
        assert_eq!(words[26 + 1], format!("{:08x}", run.gain[(0, 1)].to_bits()));
        assert_eq!(words[43], format!("{:08x}", run.p_post[(2, 2)].to_bits()));
    }
}
