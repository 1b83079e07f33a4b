//! `locus demo`: one leg of paper 001's square, EKF against odometry alone.
//!
//! The robot drives north along `wall_x+` of the 1 m arena (spec section 3:
//! path at x = 0.85 m, 0.15 m from the wall) at 0.1 m/s. Its encoders
//! over-count the right wheel by a small scale error, so odometry alone turns
//! and drifts; the two IR sensors on its right see the wall and the EKF
//! corrects x and theta (a wall cannot tell y).
//!
//! The filter is paper 001's localisation loop as every loop of Locus runs
//! it ([`locus_models::Localiser`]: prediction, association of the IR pair
//! with a wall of the arena, correction behind the gate, NIS consistency
//! monitor); the demo feeds it the noisy wheel travels and the readings.
//! The map is the arena's whole east side, the line `x = 1 m` for
//! `-1 <= y <= 1` (m), so every reading of the leg (and of a longer run,
//! `--steps` above 100) has its wall.

use anyhow::{Context, Result, bail, ensure};
use clap::Args;
use comfy_table::{Table, presets::UTF8_FULL};
use locus_core::nalgebra::{Vector2, Vector3};
use locus_core::{MotionModel, Update, wrap_angle};
use locus_models::{IrOutcome, LocaliserConfig, Segment, WheelTravel};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

/// Arguments of `locus demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Seed of the random numbers (a run is reproducible from its seed).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Number of 0.1 s steps (the leg is 1 m long at 0.1 m/s: 100 steps;
    /// readings beyond the end of the wall find no wall).
    #[arg(long, default_value_t = 100)]
    steps: usize,
    /// Standard deviation of each IR reading, m (> 0).
    #[arg(long, default_value_t = 0.005, value_parser = crate::args::positive_f64)]
    ir_sigma: f64,
    /// Right-wheel encoder scale error (0.02 = over-counts by 2 %; finite,
    /// > -1).
    #[arg(long, default_value_t = 0.02, value_parser = crate::args::finite_f64)]
    scale_error: f64,
}

const DT: f64 = 0.1; // s
const SPEED: f64 = 0.1; // m/s
const WHEELBASE: f64 = 0.12; // m
const LW: f64 = 1.0; // m
const IR_RANGE: f64 = 0.30; // m

/// Runs the demo and prints a summary table.
pub fn run(args: &DemoArgs) -> Result<()> {
    ensure!(args.steps > 0, "--steps must be at least 1");
    ensure!(
        args.ir_sigma > 0.0 && args.ir_sigma.is_finite(),
        "--ir-sigma must be > 0 (m)"
    );
    ensure!(
        args.scale_error > -1.0,
        "--scale-error must be > -1 (a wheel that travels)"
    );
    let mut rng = StdRng::seed_from_u64(args.seed);
    let ir_noise = Normal::new(0.0, args.ir_sigma).context("IR noise")?;
    let wheel_noise = Normal::new(0.0, 2e-4).context("wheel noise")?;

    let start = [0.85, -0.85, core::f64::consts::FRAC_PI_2];
    let mut localiser = LocaliserConfig {
        wheelbase: WHEELBASE,
        // The demo predicts from wheel travels (`Localiser::predict`), not
        // encoder counts: the odometer (paper 001's encoder) goes unused.
        wheel_radius: 0.028,
        encoder_lines: 90,
        encoder_gear: 1.0,
        counter_bits: 32,
        ir_spacing: 0.10,
        association_range: IR_RANGE,
        q11: 1e-6,
        q22: 4e-4,
        r11: args.ir_sigma.powi(2),
        r22: args.ir_sigma.powi(2),
        gate_confidence: Some(0.999),
        start,
        initial_std: [0.01, 0.01, 1e-3_f64.sqrt()],
    }
    .localiser()?;
    let model = localiser.model;
    let walls = [Segment::new([LW, -LW], [LW, LW])];

    let start = Vector3::from(start);
    let mut truth = start;
    let mut odo = start;
    let (mut applied, mut gated, mut unassociated, mut observations) = (0usize, 0, 0, 0);
    let mut sq = [[0.0f64; 3]; 2]; // squared errors: [ekf, odo][x, y, theta]

    for _ in 0..args.steps {
        // Truth: straight at SPEED; the wheels really travel what they should.
        let true_travel = WheelTravel {
            d1: SPEED * DT,
            d2: SPEED * DT,
        };
        truth = model.f(&truth, &true_travel, &Vector2::zeros());
        // Encoders: right wheel over-counts, both are noisy.
        let measured = WheelTravel {
            d1: true_travel.d1 * (1.0 + args.scale_error) + wheel_noise.sample(&mut rng),
            d2: true_travel.d2 + wheel_noise.sample(&mut rng),
        };
        odo = model.f(&odo, &measured, &Vector2::zeros());
        localiser.predict(&measured)?;

        // IR readings from the true pose (sensors on the right, looking right).
        let readings = [0.05, -0.05].map(|along| {
            let sensor_x = truth[0] + along * truth[2].cos();
            let beam = truth[2] - core::f64::consts::FRAC_PI_2;
            (LW - sensor_x) / beam.cos() + ir_noise.sample(&mut rng)
        });
        if readings.iter().all(|r| *r > 0.04 && *r < IR_RANGE) {
            observations += 1;
            // Associated with the wall the estimate's sensing ray hits, then
            // corrected behind the gate (its NIS goes to the monitor).
            match localiser.ir(&walls, readings)? {
                IrOutcome::Unassociated => unassociated += 1,
                IrOutcome::Associated { update, .. } => match update {
                    Update::Applied { .. } => applied += 1,
                    Update::Gated { .. } => gated += 1,
                    Update::NoMeasurement => bail!("the IR pair predicted no measurement"),
                },
            }
        }
        let ekf_belief = localiser.belief();
        for (k, est) in [ekf_belief.x, odo].iter().enumerate() {
            sq[k][0] += (est[0] - truth[0]).powi(2);
            sq[k][1] += (est[1] - truth[1]).powi(2);
            sq[k][2] += wrap_angle(est[2] - truth[2]).powi(2);
        }
    }

    let n = args.steps as f64;
    let rmse = |k: usize, i: usize| (sq[k][i] / n).sqrt();
    let mut table = Table::new();
    table.load_preset(UTF8_FULL).set_header(vec![
        "estimator",
        "RMSE x [cm]",
        "RMSE y [cm]",
        "RMSE theta [deg]",
        "final 1-sigma x [cm]",
    ]);
    table.add_row(vec![
        "EKF (odometry + IR)".to_string(),
        format!("{:.2}", 100.0 * rmse(0, 0)),
        format!("{:.2}", 100.0 * rmse(0, 1)),
        format!("{:.2}", rmse(0, 2).to_degrees()),
        format!("{:.2}", 100.0 * localiser.belief().p[(0, 0)].sqrt()),
    ]);
    table.add_row(vec![
        "odometry alone".to_string(),
        format!("{:.2}", 100.0 * rmse(1, 0)),
        format!("{:.2}", 100.0 * rmse(1, 1)),
        format!("{:.2}", rmse(1, 2).to_degrees()),
        "-".to_string(),
    ]);
    // NIS over the localiser's window of the last corrections against its
    // 95 % chi-square bounds.
    let nis = localiser.filter.monitor().assess();
    crate::output::print_out(&format!(
        "locus demo: paper 001, one leg along wall x+ ({} steps of {DT} s, seed {})\n{table}\n\
         IR observations: {observations}, applied {applied}, gated out {gated} (chi-square 99.9 %), \
         unassociated {unassociated}\n\
         NIS consistency (last {} corrections): mean {:.2} (95 % bounds {:.2}..{:.2} for dof {:.0}): {}\n",
        args.steps,
        args.seed,
        nis.samples,
        nis.mean_nis,
        nis.lower,
        nis.upper,
        nis.mean_dof,
        nis.verdict
    ))
}
