//! Guide step e) against its Q: why a Q large enough for a gain near 1 on
//! the measured wall coordinate gives a worse position RMSE than step c's
//! tiny R (the reason of spec section 3's revision of e), 2026-12-01).
//!
//! Runs step e's configuration (R = the injected IR noise, no gate) with a
//! range of `(Q11, Q22)` over the guide's seeds 1..=10, and prints the mean
//! gain on the measured wall coordinate (`H K`'s first diagonal entry,
//! `StepRecord::gain[0]`) and the position RMSE beside step c's. `Q22`
//! alone (heading noise) leaves that gain near zero however large it is;
//! only `Q11` raises it, and with it the along-wall coordinate is dragged
//! at every reading.
//!
//!     cargo run --release -p locus-sim --example guide_e_sweep
// A std-only example: the no_std lints of the workspace do not apply.
#![allow(clippy::std_instead_of_core, clippy::std_instead_of_alloc)]

use locus_sim::closed_loop::{Error, SquareConfig, StepRecord, run_square};
use locus_sim::guide::{RUNS_PER_STEP, step_config};

/// Mean position RMSE (m) and mean wall-coordinate gain over seeds
/// 1..=RUNS_PER_STEP.
fn measure(cfg: &SquareConfig) -> Result<(f64, f64), Error> {
    let (mut rmse, mut gain) = (0.0, 0.0);
    for seed in 1..=RUNS_PER_STEP {
        let (mut sum, mut n) = (0.0, 0u32);
        let summary = run_square(cfg, seed, &mut |r: &StepRecord| {
            if let Some(g) = r.gain {
                sum += g[0];
                n += 1;
            }
        })?;
        rmse += summary.position_rmse;
        gain += sum / f64::from(n.max(1));
    }
    #[allow(clippy::cast_precision_loss)]
    let runs = RUNS_PER_STEP as f64;
    Ok((rmse / runs, gain / runs))
}

fn main() -> Result<(), Error> {
    let base = SquareConfig::default();
    let unknown = Error::Config("unknown guide step");
    let c = step_config('c', &base).ok_or(unknown)?;
    let e = step_config('e', &base).ok_or(unknown)?;
    let (c_rmse, c_gain) = measure(&c)?;
    println!(
        "step c (R tiny, default Q): RMSE {:.1} cm, gain {c_gain:.3}",
        100.0 * c_rmse
    );
    println!("step e (R = (2 cm)^2), seeds 1..={RUNS_PER_STEP}:");
    println!(
        "{:>12} {:>12} {:>10} {:>10} {:>10}",
        "Q11 [m^2]", "Q22 [rad^2]", "gain", "RMSE cm", "vs c"
    );
    let qs = [
        (1e-14, 1e4),
        (1e-14, 1e6),
        (1e-14, 1e10),
        (1e-4, 1e6),
        (1e-2, 1e-2),
        (1e-1, 1e-2),
        (1.0, 1.0),
        (1.0, 1e4),
    ];
    for (q11, q22) in qs {
        let (rmse, gain) = measure(&SquareConfig { q11, q22, ..e })?;
        println!(
            "{q11:>12.0e} {q22:>12.0e} {gain:>10.3} {:>10.1} {:>+9.0}%",
            100.0 * rmse,
            100.0 * (rmse / c_rmse - 1.0)
        );
    }
    Ok(())
}
