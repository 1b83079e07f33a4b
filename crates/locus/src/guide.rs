//! `locus guide`: paper 001's guided experiment (steps a to f) with the
//! measurable criteria of spec section 3 (revised 2026-12-01), run on the
//! `square` scenario (`locus_sim::guide`), as a table with PASS/FAIL per
//! step.

use anyhow::{Result, bail};
use clap::Args;
use comfy_table::{ContentArrangement, Table, presets::UTF8_FULL};

use crate::output::print_out;

/// Arguments of `locus guide`.
#[derive(Args, Debug)]
pub struct GuideArgs {
    /// First seed: every step runs the seeds SEED..SEED+9 and reports
    /// means; step f's NEES test runs SEED..SEED+99 on `square-ideal`.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Runs the guide, prints the table; an error (non-zero exit) if a step
/// fails its criterion.
pub fn run(args: &GuideArgs) -> Result<()> {
    let steps = locus_sim::guide::run_guide(args.seed)?;
    let mut table = Table::new();
    table
        .load_preset(UTF8_FULL)
        .set_content_arrangement(ContentArrangement::Dynamic)
        .set_width(160)
        .set_header(vec![
            "step",
            "setup",
            "demonstrates",
            "measured",
            "criterion",
            "verdict",
        ]);
    for s in &steps {
        table.add_row(vec![
            format!("{})", s.step),
            s.setup.to_string(),
            s.demonstrates.to_string(),
            s.measured.clone(),
            s.criterion.to_string(),
            if s.passed { "PASS" } else { "FAIL" }.to_string(),
        ]);
    }
    let failed: Vec<String> = steps
        .iter()
        .filter(|s| !s.passed)
        .map(|s| format!("{})", s.step))
        .collect();
    print_out(&format!(
        "locus guide: paper 001's guided experiment on `square`, seeds {}..={} \
         (means over {} runs per step; IR noise 2 cm in c-f)\n{table}\n",
        args.seed,
        args.seed
            .saturating_add(locus_sim::guide::RUNS_PER_STEP - 1),
        locus_sim::guide::RUNS_PER_STEP
    ))?;
    if !failed.is_empty() {
        bail!(
            "{} of {} steps failed their criterion: {}",
            failed.len(),
            steps.len(),
            failed.join(", ")
        );
    }
    Ok(())
}
