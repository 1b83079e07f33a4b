//! The scenario argument shared by `locus robot` and `locus host`: the
//! built-in `square` or a TOML scenario file of kind `square`.

use anyhow::{Context, bail};
use locus_sim::closed_loop::SquareConfig;
use locus_sim::scenario_file::{Scenario, ScenarioConfig};

use crate::args::ScenarioArg;

/// The `square` configuration named by `scenario` (`square` or a file).
pub fn square_config(scenario: &ScenarioArg) -> anyhow::Result<SquareConfig> {
    if let ScenarioArg::Builtin(s) = scenario {
        if *s != Scenario::Square {
            bail!("the robot link runs `square` or a scenario file of kind `square`, not `{s}`");
        }
    }
    let config = scenario
        .config()
        .with_context(|| format!("reading {scenario}"))?;
    match config {
        ScenarioConfig::Square(c) => Ok(c),
        _ => bail!("the robot link runs `square` scenarios only (paper 001's robot)"),
    }
}
