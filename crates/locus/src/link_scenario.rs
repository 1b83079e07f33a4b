//! The scenario argument shared by `locus robot` and `locus host`: the
//! built-in `square` or a TOML scenario file of kind `square`.

use std::path::Path;

use anyhow::{Context, bail};
use locus_sim::closed_loop::SquareConfig;
use locus_sim::scenario_file::{ScenarioConfig, load};

/// The `square` configuration named by `scenario` (`square` or a file).
pub fn square_config(scenario: &str) -> anyhow::Result<SquareConfig> {
    let config = if scenario == "square" {
        ScenarioConfig::builtin(scenario)
            .with_context(|| format!("no built-in scenario `{scenario}`"))?
    } else {
        load(Path::new(scenario)).with_context(|| format!("reading {scenario}"))?
    };
    match config {
        ScenarioConfig::Square(c) => Ok(c),
        _ => bail!("the robot link runs `square` scenarios only (paper 001's robot)"),
    }
}
