//! Writes the firmware's recorded sequence,
//! `firmware/locus-fw-app/src/square_data.rs`, from a seeded `square` run
//! (see `locus_sim::firmware_data`). Run from anywhere in the repository:
//!
//! ```text
//! cargo run -p locus-sim --example firmware_data
//! ```

use std::path::Path;
use std::process::ExitCode;

use locus_sim::firmware_data::{OUTPUT_PATH, SEED, STEPS, generate};

fn main() -> ExitCode {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let path = root.join(OUTPUT_PATH);
    match generate(SEED, STEPS) {
        Ok(source) => match std::fs::write(&path, source) {
            Ok(()) => {
                println!("wrote {}", path.display());
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: writing {}: {e}", path.display());
                ExitCode::FAILURE
            }
        },
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
