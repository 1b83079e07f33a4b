//! `locus hw` and the Verilog correction core (`hdl/`): the vectors the
//! command exports from the Rust models drive the core, compiled by
//! Verilator, over 10 000 random corrections and under Icarus Verilog over
//! every correction of a `wall45` run: G, X+ and P+ bit-exact and the
//! cycles the model's. And `locus hw` prints the simulated figure beside
//! the model's and the paper's.

use std::process::Command;

use locus_hw::hdl::ekf_core::{CoreSim, CoreSimReport};
use locus_hw::{self as hw, Schedule};

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
    let cfg = locus_hw::hdl::built_config().unwrap();
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

#[test]
fn locus_hw_prints_the_placed_and_routed_row_or_why_not() {
    let row = |out: &str, label: &str| {
        out.lines()
            .find(|l| l.contains(label))
            .unwrap_or_else(|| panic!("no row {label}: {out}"))
            .to_owned()
    };
    let c = model_cycles().to_string();
    // No flow run given: n/a, and how to get one.
    let out = locus(&["hw", "--no-sim"]);
    let none = row(&out, "│ this core ");
    assert!(
        none.contains(&c) && none.contains("n/a: not given: run `bash scripts/hw_pnr.sh`"),
        "{none}"
    );
    assert!(row(&out, "papers 000/003 (EP4CE115").contains("22089 LEs"));
    // A flow run's report (nextpnr 0.11's shape): its Fmax and cells, and
    // the time at the model's cycles.
    let dir = std::env::temp_dir().join(format!("locus-hw-pnr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let d = dir.to_str().unwrap();
    let out = locus(&["hw", "--no-sim", "--pnr", d]);
    assert!(
        row(&out, "│ this core ").contains("report.json is missing"),
        "{out}"
    );
    std::fs::write(
        dir.join("report.json"),
        r#"{"fmax": {"$glbnet$clk": {"achieved": 50.0, "constraint": 50}},
           "utilization": {"TRELLIS_COMB": {"used": 20000, "available": 83640},
           "TRELLIS_FF": {"used": 21000, "available": 83640},
           "MULT18X18D": {"used": 40, "available": 156}}}"#,
    )
    .unwrap();
    let out = locus(&["hw", "--no-sim", "--pnr", d]);
    let placed = row(&out, "this core (nextpnr-ecp5)");
    let us = format!("{:.2}", model_cycles() as f64 / 50.0);
    for want in [
        c.as_str(),
        "50.00",
        us.as_str(),
        "20000",
        "21000",
        "40 MULT18X18D",
    ] {
        assert!(placed.contains(want), "{want}: {placed}");
    }
    std::fs::write(dir.join("report.json"), "{").unwrap();
    let err = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["hw", "--no-sim", "--pnr", d])
        .output()
        .unwrap();
    assert!(!err.status.success());
    assert!(String::from_utf8_lossy(&err.stderr).contains("not a nextpnr report"));
    let _ = std::fs::remove_dir_all(&dir);
}
