//! `locus tune` as a user runs it on MRCLAM dataset 6: by default it
//! prints the process noise and the odometry delay found from robots 1-3's
//! logs alone, which is how the replay's defaults were made.

use std::process::Command;

#[test]
fn tune_prints_the_noise_the_defaults_were_made_from() {
    let data = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/mrclam/MRCLAM_Dataset6"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["tune", data])
        .output()
        .expect("run locus");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let row = |label: &str| -> (f64, f64) {
        let line = text
            .lines()
            .find(|l| l.starts_with('│') && l.contains(label))
            .unwrap_or_else(|| panic!("no {label} in\n{text}"));
        let cells: Vec<f64> = line
            .split(['┆', '│'])
            .filter_map(|c| c.trim().parse().ok())
            .collect();
        (cells[0], cells[1])
    };
    assert!(text.contains("objective Drift"), "{text}");
    for label in ["q_v, forward-speed", "q_omega, turn-rate"] {
        let (default, tuned) = row(label);
        assert!(
            tuned / default < 1.5 && default / tuned < 1.5,
            "{label}: {tuned} against {default}"
        );
    }
    let (_, delay) = row("odometry delay");
    assert!((0.1..=0.3).contains(&delay), "{delay}");
    assert!(text.contains("held out"), "{text}");
}
