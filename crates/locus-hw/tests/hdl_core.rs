//! The correction core in Verilog (`hdl/core/ekf_core.v`, on the units of
//! `hdl/fp/`) under Icarus Verilog against the software `f32` 11-step
//! schedule (`locus_hw::run`): bit-exact `G`, `X+` and `P+` on
//! random corrections of realistic magnitude, the cycles from start to done
//! and per FSM state equal to the cycle-level model's with the units'
//! latencies, and a wrong expected word reported. The 10 000 corrections
//! and the `wall45` run are in `crates/locus/tests/hw_rtl.rs`.

use std::time::Instant;

use locus_hw::hdl;
use locus_hw::hdl::ekf_core::{self, CoreSim};
use locus_hw::{self as hw, Schedule};

#[test]
fn the_core_is_bit_exact_and_takes_the_models_cycles() {
    let cfg = hdl::built_config().unwrap();
    let inputs = ekf_core::random_inputs(50, 5);
    let t = Instant::now();
    let report = CoreSim::Icarus
        .run(&cfg, &inputs)
        .unwrap_or_else(|e| panic!("{e}"));
    let model = hw::run(&cfg, Schedule::Inverse2x2, &inputs[0]).unwrap();
    println!(
        "Icarus: {} corrections, {} mismatching words, {}..{} cycles (model {}), {:.1} s",
        report.corrections,
        report.mismatches,
        report.cycles_min,
        report.cycles_max,
        model.cycles,
        t.elapsed().as_secs_f64()
    );
    assert_eq!((report.corrections, report.mismatches), (50, 0));
    assert_eq!(
        (report.cycles_min, report.cycles_max),
        (model.cycles, model.cycles)
    );
    println!("per state: {:?}", report.cycles_per_state());
    assert_eq!(report.cycles_per_state(), model.cycles_per_state());
}

/// One wrong expected word: the testbench must report it (so a passing
/// run means the results were compared).
#[test]
fn a_wrong_expected_result_is_reported() {
    let cfg = hdl::built_config().unwrap();
    let inputs = ekf_core::random_inputs(3, 8);
    let dir = hdl::TempDir::new("core-corrupt").unwrap();
    let path = dir.path().join("core.txt");
    ekf_core::write_vectors(&path, &cfg, &inputs).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    // Flip the last bit of correction 1's P+[2][2] (its last word).
    let mut words: Vec<String> = lines[1].split(' ').map(str::to_owned).collect();
    let last = u32::from_str_radix(&words[43], 16).unwrap() ^ 1;
    words[43] = format!("{last:08x}");
    lines[1] = words.join(" ");
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    let report = CoreSim::Icarus.run_file(&path).unwrap();
    assert_eq!((report.corrections, report.mismatches), (3, 1));
}
