//! The firmware's embedded sequence (`firmware/locus-fw-app/src/square_data.rs`)
//! is exactly what the generator produces from the simulator today: a change
//! of the simulator, its defaults or the generator that would change the
//! recorded data fails here until the file is regenerated with
//! `cargo run -p locus-sim --example firmware_data`.

use std::path::Path;

use locus_sim::firmware_data::{OUTPUT_PATH, SEED, STEPS, generate};

#[test]
fn the_committed_firmware_data_is_the_generators_output() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(OUTPUT_PATH);
    let committed = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    let fresh = generate(SEED, STEPS).expect("generation");
    if committed != fresh {
        let line = committed
            .lines()
            .zip(fresh.lines())
            .position(|(a, b)| a != b)
            .map_or_else(
                || "the line counts".to_owned(),
                |i| format!("line {}", i + 1),
            );
        panic!(
            "{} differs from the generator's output (first difference at {line}); \
             regenerate it with `cargo run -p locus-sim --example firmware_data`",
            path.display()
        );
    }
}

#[test]
fn the_waveform_has_at_most_one_edge_per_sample_and_the_ir_readings_are_in_range() {
    let source = generate(SEED, 400).expect("generation");
    let mut words = 0;
    let mut previous = 0u32; // levels 00 on both wheels at the start
    let phase = |a: u32, b: u32| [0u32, 3, 1, 2][((a << 1) | b) as usize];
    for line in source.lines().filter(|l| l.trim_start().starts_with("0x")) {
        for word in line.split_whitespace() {
            let v = u32::from_str_radix(word.trim_end_matches(',').trim_start_matches("0x"), 16)
                .expect("hex word");
            words += 1;
            for j in 0..8 {
                let n = (v >> (4 * j)) & 0xf;
                for wheel in 0..2 {
                    let (a, b) = ((n >> (2 * wheel)) & 1, (n >> (2 * wheel + 1)) & 1);
                    let (pa, pb) = (
                        (previous >> (2 * wheel)) & 1,
                        (previous >> (2 * wheel + 1)) & 1,
                    );
                    let delta = (phase(a, b) + 4 - phase(pa, pb)) % 4;
                    assert_ne!(
                        delta, 2,
                        "two edges in one sample (word {words}, sample {j})"
                    );
                }
                previous = n;
            }
        }
    }
    assert_eq!(words, 400);
    let readings: Vec<f32> = source
        .lines()
        .filter_map(|l| l.trim().strip_prefix("Some([")?.strip_suffix("]),"))
        .flat_map(|pair| {
            pair.split(", ")
                .map(|v| v.parse::<f32>().expect("f32"))
                .collect::<Vec<_>>()
        })
        .collect();
    assert!(readings.len() > 200, "{} readings", readings.len());
    assert!(readings.iter().all(|d| (0.04..=0.30).contains(d)));
}
