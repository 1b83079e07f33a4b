//! The recorded sequence the Cortex-M4F firmware replays: the
//! first steps of a seeded `square` run ([`run_square`], paper 001's closed
//! loop), written as a Rust source file of constants for
//! `firmware/locus-fw-app/src/square_data.rs`.
//!
//! What is recorded, per 10 ms step:
//! * **the quadrature waveform** of both wheels: the channel levels `(A, B)`
//!   sampled [`SAMPLES_PER_STEP`] times per step (800 Hz). The simulator's
//!   encoders ([`crate::sensors::Encoder`]) produce, per step, the edges
//!   crossed by the wheel (after slip and the right wheel's calibration
//!   error), decoded into the wheel travels the simulator's own filter uses
//!   (`StepRecord::wheel_travel`, an exact multiple of the count quantum).
//!   The generator recovers that signed count `n` per step and lays its edges
//!   evenly over the step: sample `j` (0-based) shows the levels of count
//!   `C + trunc(n (j + 1) / S)`, `C` the count at the start of the step, in
//!   the x4 phase order 00, 10, 11, 01 (forward = counting up), so the last
//!   sample of the step is at `C + n`. The generator fails if a step has more
//!   than [`SAMPLES_PER_STEP`] edges (two edges in one sample would be an
//!   invalid transition);
//! * **the IR pair's readings** `(d_s1, d_s2)` (m) when both were in range;
//!   the firmware does the data association itself, on its own estimate.
//!
//! Every `f64` is rounded to the nearest `f32` here and written in Rust's
//! shortest round-trip form, so the constants are exactly the `f32`s the
//! firmware and the host reference run read. The gate's 2-dof threshold
//! `chi2_2(0.99)` is computed here (`locus_core::chi2::quantile`), so the
//! firmware does not carry the quantile's special functions. The configuration
//! ([`SquareConfig::default`]), the arena's walls and, for a sanity check of
//! the `f32` filter, the simulator's own `f64` estimate and the truth at the
//! last recorded step are written too.
//!
//! `cargo run -p locus-sim --example firmware_data` rewrites the file;
//! `tests/firmware_data.rs` fails if the committed file differs.

use core::fmt::Write as _;

use locus_odometry::Wheel;

use crate::closed_loop::{Error, SquareConfig, StepRecord, run_square};
use crate::world::World;

/// Samples of the channel levels per step (must match the firmware's
/// `locus_fw_app::SAMPLES_PER_STEP`).
pub const SAMPLES_PER_STEP: usize = 8;

/// Seed of the recorded run.
pub const SEED: u64 = 1;

/// Steps recorded (30 s at 10 ms: the first side of the square along wall
/// `y-`, the first corner, and the start of the second side along `x+`).
pub const STEPS: usize = 3000;

/// Path of the generated file, relative to the repository root.
pub const OUTPUT_PATH: &str = "firmware/locus-fw-app/src/square_data.rs";

/// Errors of the generation.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GenerateError {
    /// The simulation failed.
    #[error("simulation: {0}")]
    Sim(#[from] Error),
    /// The run ended before `steps` steps.
    #[error("the run has only {0} steps")]
    TooShort(usize),
    /// A step's wheel travel is not a whole number of counts.
    #[error("step {step}: wheel travel {travel} m is not a whole number of counts")]
    NotWholeCounts {
        /// The step.
        step: usize,
        /// The travel, m.
        travel: f64,
    },
    /// The configuration has no gate (the firmware gates at 99 %).
    #[error("the square configuration has no gate")]
    NoGate,
    /// A step has more edges than samples.
    #[error("step {step}: {counts} counts do not fit in {SAMPLES_PER_STEP} samples")]
    TooFast {
        /// The step.
        step: usize,
        /// Its count.
        counts: i64,
    },
}

/// The levels `(A, B)` of x4 phase `count mod 4` (00, 10, 11, 01).
fn levels(count: i64) -> (bool, bool) {
    match count.rem_euclid(4) {
        0 => (false, false),
        1 => (true, false),
        2 => (true, true),
        _ => (false, true),
    }
}

/// The nibble of one sample: bit 0 right A, bit 1 right B, bit 2 left A,
/// bit 3 left B.
fn nibble(right: i64, left: i64) -> u32 {
    let (ra, rb) = levels(right);
    let (la, lb) = levels(left);
    u32::from(ra) | u32::from(rb) << 1 | u32::from(la) << 2 | u32::from(lb) << 3
}

/// Writes `v` (rounded to `f32`) as a Rust `f32` literal that parses back to
/// exactly that `f32`.
#[allow(clippy::cast_possible_truncation)]
fn f32_literal(v: f64) -> String {
    let f = v as f32;
    let s = format!("{f:?}");
    if s.contains('.') || s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

/// The Rust source of the recorded sequence: `steps` steps of the default
/// `square` run from `seed`.
///
/// # Errors
/// See [`GenerateError`].
#[allow(clippy::cast_possible_truncation, clippy::too_many_lines)]
pub fn generate(seed: u64, steps: usize) -> Result<String, GenerateError> {
    let cfg = SquareConfig::default();
    let mut records: Vec<StepRecord> = Vec::with_capacity(steps);
    run_square(&cfg, seed, &mut |r: &StepRecord| {
        if records.len() < steps {
            records.push(*r);
        }
    })?;
    if records.len() < steps {
        return Err(GenerateError::TooShort(records.len()));
    }
    let wheel = Wheel::new(cfg.encoder_lines, cfg.encoder_gear, cfg.wheel_radius);
    let quantum = wheel.quantum();
    let counts_of = |step: usize, travel: f64| -> Result<i64, GenerateError> {
        let n = (travel / quantum).round();
        if (travel - n * quantum).abs() > 1e-9 * quantum.max(travel.abs()) {
            return Err(GenerateError::NotWholeCounts { step, travel });
        }
        let n = n as i64;
        if n.unsigned_abs() > SAMPLES_PER_STEP as u64 {
            return Err(GenerateError::TooFast { step, counts: n });
        }
        Ok(n)
    };

    let mut waveform = Vec::with_capacity(steps);
    let (mut right, mut left) = (0i64, 0i64);
    let mut max_counts = 0i64;
    for r in &records {
        let nr = counts_of(r.step, r.wheel_travel[0])?;
        let nl = counts_of(r.step, r.wheel_travel[1])?;
        max_counts = max_counts.max(nr.abs()).max(nl.abs());
        let mut word = 0u32;
        for j in 0..SAMPLES_PER_STEP as i64 {
            let s = SAMPLES_PER_STEP as i64;
            let nib = nibble(right + nr * (j + 1) / s, left + nl * (j + 1) / s);
            word |= nib << (4 * j);
        }
        waveform.push(word);
        right += nr;
        left += nl;
    }

    let mut out = String::new();
    let w = &mut out;
    let _ = writeln!(
        w,
        "//! GENERATED by `cargo run -p locus-sim --example firmware_data` from\n\
         //! `locus_sim::firmware_data` (do not edit; `cargo test -p locus-sim --test\n\
         //! firmware_data` fails if this file differs from a fresh generation).\n\
         //!\n\
         //! The first {steps} steps (10 ms each) of the default `square` run from seed\n\
         //! {seed}: per step, the quadrature levels of both wheels ({SAMPLES_PER_STEP} samples)\n\
         //! and the IR pair's readings; the run's configuration and the arena. See\n\
         //! `crates/locus-sim/src/firmware_data.rs` for how the waveform is laid out.\n\
         //! Max counts in one step: {max_counts}; final counts right {right}, left {left}."
    );
    let _ = writeln!(w);
    let _ = writeln!(w, "use locus_models::Segment;");
    let _ = writeln!(w);
    let _ = writeln!(w, "use crate::Config;");
    let _ = writeln!(w);
    let _ = writeln!(w, "/// Steps recorded.");
    let _ = writeln!(w, "pub const STEPS: usize = {steps};");
    let _ = writeln!(w);
    let _ = writeln!(w, "/// Seed of the recorded simulator run.");
    let _ = writeln!(w, "pub const SEED: u64 = {seed};");
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "/// The run's configuration (`SquareConfig::default()`)."
    );
    let _ = writeln!(w, "pub const CONFIG: Config = Config {{");
    let _ = writeln!(w, "    wheelbase: {},", f32_literal(cfg.wheelbase));
    let _ = writeln!(w, "    wheel_radius: {},", f32_literal(cfg.wheel_radius));
    let _ = writeln!(w, "    encoder_lines: {},", cfg.encoder_lines);
    let _ = writeln!(w, "    q11: {},", f32_literal(cfg.q11));
    let _ = writeln!(w, "    q22: {},", f32_literal(cfg.q22));
    let _ = writeln!(w, "    r11: {},", f32_literal(cfg.r11));
    let _ = writeln!(w, "    r22: {},", f32_literal(cfg.r22));
    let _ = writeln!(w, "    ir_spacing: {},", f32_literal(cfg.ir_spacing));
    let _ = writeln!(
        w,
        "    association_range: {},",
        f32_literal(cfg.association_range)
    );
    let gate = cfg.gate_confidence.ok_or(GenerateError::NoGate)?;
    let threshold = locus_core::chi2::quantile(gate, 2).map_err(Error::from)?;
    let _ = writeln!(w, "    gate_confidence: {gate:?},");
    let _ = writeln!(w, "    gate_threshold: {},", f32_literal(threshold));
    let [s0, s1, s2] = cfg.start.map(f32_literal);
    let _ = writeln!(w, "    start: [{s0}, {s1}, {s2}],");
    let [d0, d1, d2] = cfg.initial_std.map(f32_literal);
    let _ = writeln!(w, "    initial_std: [{d0}, {d1}, {d2}],");
    let _ = writeln!(w, "}};");
    let _ = writeln!(w);
    let _ = writeln!(w, "/// The arena's walls (m), `World::square_arena()`.");
    let _ = writeln!(w, "pub static ARENA: [Segment<f32>; 4] = [");
    for s in &World::square_arena().walls {
        let _ = writeln!(
            w,
            "    Segment::new([{}, {}], [{}, {}]),",
            f32_literal(s.a[0]),
            f32_literal(s.a[1]),
            f32_literal(s.b[0]),
            f32_literal(s.b[1])
        );
    }
    let _ = writeln!(w, "];");
    let _ = writeln!(w);
    let last = &records[steps - 1];
    let _ = writeln!(
        w,
        "/// The simulator's `f64` EKF estimate `[x, y, theta]` after the last step."
    );
    let _ = writeln!(
        w,
        "pub const SIM_ESTIMATE: [f64; 3] = [{:?}, {:?}, {:?}];",
        last.ekf[0], last.ekf[1], last.ekf[2]
    );
    let _ = writeln!(
        w,
        "/// The simulator's decoded counts `[right, left]` after the last step\n\
         /// (sums of the per-step counts; the decoders' 20-bit counters wrap them)."
    );
    let _ = writeln!(w, "pub const SIM_COUNTS: [i64; 2] = [{right}, {left}];");
    let _ = writeln!(w, "/// The true pose `[x, y, theta]` after the last step.");
    let _ = writeln!(
        w,
        "pub const TRUTH: [f64; 3] = [{:?}, {:?}, {:?}];",
        last.truth.x, last.truth.y, last.truth.theta
    );
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "/// Per step, the {SAMPLES_PER_STEP} samples of the channel levels (nibble `j` = sample `j`:\n\
         /// bit 0 right A, bit 1 right B, bit 2 left A, bit 3 left B)."
    );
    let _ = writeln!(w, "pub static WAVEFORM: [u32; STEPS] = [");
    for chunk in waveform.chunks(8) {
        let line: Vec<String> = chunk.iter().map(|v| format!("0x{v:08x},")).collect();
        let _ = writeln!(w, "    {}", line.join(" "));
    }
    let _ = writeln!(w, "];");
    let _ = writeln!(w);
    let _ = writeln!(
        w,
        "/// Per step, the IR readings `[d_s1, d_s2]` (m) when both were in range."
    );
    let _ = writeln!(w, "pub static IR: [Option<[f32; 2]>; STEPS] = [");
    for r in &records {
        match r.ir {
            Some((a, b)) => {
                let _ = writeln!(w, "    Some([{}, {}]),", f32_literal(a), f32_literal(b));
            }
            None => {
                let _ = writeln!(w, "    None,");
            }
        }
    }
    let _ = writeln!(w, "];");
    Ok(out)
}
