//! `locus hw` and the Verilog correction core (`hdl/`): the vectors the
//! command exports from the Rust models drive the core, compiled by
//! Verilator, over 10 000 random corrections and under Icarus Verilog over
//! every correction of a `wall45` run: G, X+ and P+ bit-exact and the
//! cycles the model's. And `locus hw` prints the simulated figure beside
//! the model's and the paper's.

use std::process::Command;

use locus_hw::hdl::ekf_core::{CoreSim, CoreSimReport};
use locus_hw::{self as hw, HwConfig, Schedule};

fn locus(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(args)
        .output()
        .expect("run locus");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The model's cycles per correction with the units' latencies.
fn model_cycles() -> u64 {
    let cfg = HwConfig {
        latencies: locus_hw::hdl::built_latencies().unwrap(),
        ..HwConfig::default()
    };
    let inp = locus_hw::hdl::ekf_core::random_inputs(1, 1)[0];
    hw::run(&cfg, Schedule::Inverse2x2, &inp).unwrap().cycles
}

fn check(name: &str, r: &CoreSimReport, corrections: u64) {
    println!(
        "{name}: {} corrections, {} mismatching words, {}..{} cycles",
        r.corrections, r.mismatches, r.cycles_min, r.cycles_max
    );
    assert_eq!((r.corrections, r.mismatches), (corrections, 0), "{name}");
    let c = model_cycles();
    assert_eq!((r.cycles_min, r.cycles_max), (c, c), "{name}");
}

#[test]
fn the_exported_corrections_run_bit_exact_on_the_verilog_core() {
    let dir = std::env::temp_dir().join(format!("locus-hw-rtl-{}", std::process::id()));
    let dir_s = dir.to_str().unwrap();
    let out = locus(&["hw", "--export-vectors", dir_s, "--unit-vectors", "1000"]);
    println!("{out}");
    assert!(out.contains("10000 random corrections"), "{out}");
    let wall45 = std::fs::read_to_string(dir.join("core_wall45.txt")).unwrap();
    let n_wall45 = wall45.lines().count() as u64;
    assert!(n_wall45 > 100, "{n_wall45} wall45 corrections");

    let icarus = CoreSim::Icarus
        .run_file(&dir.join("core_wall45.txt"))
        .unwrap_or_else(|e| panic!("{e}"));
    check("wall45, Icarus", &icarus, n_wall45);
    let verilator = CoreSim::verilator().unwrap_or_else(|e| panic!("{e}"));
    let random = verilator
        .run_file(&dir.join("core_random.txt"))
        .unwrap_or_else(|e| panic!("{e}"));
    check("random, Verilator", &random, 10_000);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn locus_hw_prints_the_simulated_cycles_beside_the_model_and_the_paper() {
    let out = locus(&["hw"]);
    let row = |label: &str| {
        out.lines()
            .find(|l| l.contains(label))
            .unwrap_or_else(|| panic!("no row {label}: {out}"))
            .to_owned()
    };
    let c = model_cycles().to_string();
    let sim = row("simulated (Icarus Verilog)");
    assert!(sim.contains(&c) && sim.contains("bit-exact"), "{sim}");
    assert!(row("model, same latencies").contains(&c));
    assert!(row("paper 003").contains("2.08"));
}
