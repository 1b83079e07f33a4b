//! Host-only checks of the firmware application (no emulation): the
//! precomputed gate threshold is the filter's own gate, the decoders count
//! what the simulator's encoders counted, and the run keeps its checksum.

use locus_core::ChiSquareGate;
use locus_fw_app::{Firmware, run, run_with, square_data::CONFIG};

#[test]
fn the_embedded_threshold_is_the_f32_gates_2_dof_threshold() {
    let gate = ChiSquareGate::<f32>::new(CONFIG.gate_confidence).expect("gate");
    assert_eq!(
        CONFIG.gate_threshold.to_bits(),
        gate.threshold(2).to_bits(),
        "regenerate square_data.rs: threshold {} vs {}",
        CONFIG.gate_threshold,
        gate.threshold(2)
    );
}

#[test]
fn gating_on_the_threshold_equals_the_filters_gate_bit_for_bit() {
    let ours = run().expect("run");
    let library = run_with(Firmware::with_library_gate(&CONFIG).expect("gate")).expect("run");
    assert_eq!(ours, library);
    // The gate did reject something, so the comparison covers both branches.
    assert!(ours.rejected > 0 && ours.corrections > 0, "{ours:?}");
}

#[test]
fn a_nan_threshold_is_refused() {
    let mut cfg = CONFIG;
    cfg.gate_threshold = f32::NAN;
    assert!(Firmware::new(&cfg).is_err());
}

#[test]
fn the_decoders_count_what_the_simulators_encoders_counted() {
    let report = run().expect("run");
    let wrap = |c: i64| u32::try_from(c.rem_euclid(1 << 20)).expect("20 bits");
    assert_eq!(
        report.counts,
        [
            wrap(locus_fw_app::square_data::SIM_COUNTS[0]),
            wrap(locus_fw_app::square_data::SIM_COUNTS[1])
        ]
    );
    assert_eq!(report.invalid_transitions, 0);
}

#[test]
fn the_run_keeps_its_documented_checksum() {
    // docs/firmware.md: the checksum over the 3000 steps of
    // `square_data` (regenerating the data changes it; update the docs).
    let report = run().expect("run");
    assert_eq!(report.checksum, 0xfd50_52b4, "{report:?}");
    // The localiser's NIS monitor saw the corrections (its window is full).
    let mut fw = Firmware::new(&CONFIG).expect("firmware");
    for (samples, ir) in locus_fw_app::square_data::WAVEFORM
        .iter()
        .zip(locus_fw_app::square_data::IR.iter())
    {
        fw.step(*samples, *ir).expect("step");
    }
    assert_eq!(fw.report(), report);
    assert!(fw.localiser().filter.monitor().is_full());
}
