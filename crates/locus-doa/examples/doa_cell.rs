//! One grid cell of the DOA study, timed: the worst settling time over the
//! 64 vertices at `m_zeta` (64 runs of 600 observer steps at the defaults),
//! single-threaded. `scripts/doa_numpy.py` runs this and its numpy twin side
//! by side and prints the ratio.
//!
//! `cargo run --release -p locus-doa --example doa_cell -- V_G ALPHA M_ZETA REPEATS`
//! prints one line: `worst_settle_s=<s> seconds_per_cell=<s> steps=<n>`.

use std::time::Instant;

use locus_doa::{DoaConfig, Study, VERTICES};

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("numbers: V_G ALPHA M_ZETA REPEATS"))
        .collect();
    let (v_g, alpha, m) = (
        args.first().copied().unwrap_or(0.0151),
        args.get(1).copied().unwrap_or(50.0),
        args.get(2).copied().unwrap_or(0.1),
    );
    let repeats = args.get(3).copied().unwrap_or(5.0) as usize;
    let study = Study::new(DoaConfig::default()).expect("default configuration");
    let observer = study.observer(alpha);
    let mut best = f64::INFINITY;
    let mut worst = None;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        worst = study.worst_settle(&observer, v_g, m);
        best = best.min(t.elapsed().as_secs_f64());
    }
    let steps = VERTICES * study.config().run.steps();
    match worst {
        Some(s) => println!("worst_settle_s={s} seconds_per_cell={best} steps={steps}"),
        None => println!("worst_settle_s=none seconds_per_cell={best} steps={steps}"),
    }
}
