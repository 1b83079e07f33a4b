//! Issue 31: every `metrics.json` (`locus run`, a Monte Carlo, `locus
//! replay` with and without `--smooth`, with and without ground truth, and
//! judged against relations, `locus replay carmen --relations`)
//! validates against `docs/metrics.schema.json`; a replay's has no key of
//! the simulator (`ir_*`, `sim_*`, `*laps*`); the files of the old shape
//! (`tests/fixtures/metrics-v1-*.json`) do not validate.

use std::fs;
use std::path::Path;
use std::process::Command;

use serde_json::Value;

mod common;
use common::{arc_log, scratch};

/// `docs/metrics.schema.json`, compiled.
fn validator() -> jsonschema::Validator {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../docs/metrics.schema.json"
    );
    let schema: Value =
        serde_json::from_str(&fs::read_to_string(path).expect("the schema")).expect("JSON");
    jsonschema::draft202012::options()
        .should_validate_formats(true)
        .build(&schema)
        .expect("a valid JSON Schema")
}

/// The errors of `metrics` against the schema, one line each.
fn errors(validator: &jsonschema::Validator, metrics: &Value) -> Vec<String> {
    validator
        .iter_errors(metrics)
        .map(|e| format!("{}: {e}", e.instance_path()))
        .collect()
}

/// Runs `locus` with `args` and `--out out --no-plots`, and reads the
/// `metrics.json` it wrote.
fn metrics_of(args: &[&str], out: &Path) -> Value {
    let o = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(args)
        .arg("--out")
        .arg(out)
        .arg("--no-plots")
        .output()
        .expect("run locus");
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = fs::read_to_string(out.join("metrics.json")).expect("metrics.json");
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{args:?}: {e}\n{text}"))
}

/// Every key of `v`, at any depth, with its path.
fn keys(v: &Value, path: &str, out: &mut Vec<String>) {
    if let Value::Object(members) = v {
        for (k, child) in members {
            out.push(format!("{path}/{k}"));
            keys(child, &format!("{path}/{k}"), out);
        }
    }
}

/// The keys of `v` that belong to the simulator.
fn simulator_keys(v: &Value) -> Vec<String> {
    let mut all = Vec::new();
    keys(v, "", &mut all);
    all.into_iter()
        .filter(|p| {
            let k = p.rsplit('/').next().unwrap_or_default();
            k.starts_with("ir_") || k.starts_with("sim_") || k.contains("laps")
        })
        .collect()
}

#[test]
fn every_source_writes_metrics_that_validate_against_the_schema() {
    let validator = validator();
    let dir = scratch("sources");
    let s = |p: &Path| p.to_str().expect("utf-8").to_owned();
    let mut files: Vec<(String, Value)> = Vec::new();

    let run = dir.join("run");
    files.push((
        "run".into(),
        metrics_of(&["run", "square", "--laps", "1"], &run),
    ));
    let mc = dir.join("monte-carlo");
    files.push((
        "monte carlo".into(),
        metrics_of(&["run", "square", "--laps", "1", "--runs", "3"], &mc),
    ));
    let wall = dir.join("wall45");
    files.push(("wall45".into(), metrics_of(&["run", "wall45"], &wall)));

    for (name, truth) in [("with-truth", true), ("no-truth", false)] {
        let log = dir.join(format!("{name}.csv"));
        fs::write(&log, arc_log(truth, "").0).unwrap();
        let out = dir.join(format!("replay-{name}"));
        files.push((
            format!("replay {name}"),
            metrics_of(&["replay", "csv", &s(&log), "--smooth"], &out),
        ));
    }
    let mrclam = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/mrclam/MRCLAM_Dataset6"
    );
    if Path::new(mrclam).is_dir() {
        for (name, flags) in [("mrclam", &[][..]), ("mrclam smoothed", &["--smooth"])] {
            let out = dir.join(name.replace(' ', "-"));
            let args = [&["replay", "mrclam", mrclam, "--robot", "1"][..], flags].concat();
            files.push((name.into(), metrics_of(&args, &out)));
        }
    } else {
        eprintln!("note: {mrclam} not found; the MRCLAM replays are skipped");
    }
    let intel = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/intel_lab"
    );
    if Path::new(intel).is_dir() {
        // The Intel lab judged against its relations: the `relations`
        // section (a map first, from its corrected poses).
        let log = format!("{intel}/intel-corrected.log.gz");
        let map = dir.join("intel-map");
        let o = Command::new(env!("CARGO_BIN_EXE_locus"))
            .args(["map", "--carmen", &log, "--out", &s(&map)])
            .output()
            .expect("run locus map");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let args = [
            "replay",
            "carmen",
            &log,
            "--map",
            &s(&map.join("map.yaml")),
            "--relations",
            &format!("{intel}/intel.relations.xz"),
            "--no-estimate",
            "--smooth",
        ];
        files.push((
            "intel relations".into(),
            metrics_of(&args, &dir.join("intel")),
        ));
    } else {
        eprintln!("note: {intel} not found; the Intel lab's replay is skipped");
    }

    for (name, m) in &files {
        let e = errors(&validator, m);
        assert!(e.is_empty(), "{name}:\n{}\n{m:#}", e.join("\n"));
        assert_eq!(m["schema"], "locus-metrics/2", "{name}");
    }
    let by_name = |n: &str| &files.iter().find(|(name, _)| name == n).unwrap().1;

    // A replay's file has nothing of the simulator; the smoother's figures
    // have the filter's keys.
    for (name, m) in files.iter().filter(|(_, m)| m["source"] == "replay") {
        assert_eq!(simulator_keys(m), Vec::<String>::new(), "{name}");
        if let Some(smoother) = m.get("smoother") {
            let names = |v: &Value| v.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
            assert_eq!(names(smoother), names(&m["filter"]), "{name}");
        }
    }
    let smoothed = by_name("replay with-truth");
    assert!(
        smoothed["smoother"]["within_3_sigma_x_share"].is_f64(),
        "{smoothed:#}"
    );
    assert!(smoothed["calibration"]["speed_scale"]["mean"].is_f64());
    // No truth: n/a (null), never 0; the counts are there.
    let bare = by_name("replay no-truth");
    assert!(bare["filter"]["position_rmse_m"].is_null(), "{bare:#}");
    assert!(bare["smoother"]["position_rmse_m"].is_null(), "{bare:#}");
    assert_eq!(bare["counts"]["applied"], 57, "{bare:#}");
    // The simulator's own section, only for runs.
    assert_eq!(by_name("run")["simulation"]["laps_completed"], 1);
    assert!(by_name("wall45")["simulation"].get("laps").is_none());
    assert_eq!(by_name("monte carlo")["monte_carlo"]["runs"], 3);
    // The relations section only where asked for, with the smoother's
    // figures beside the filter's when smoothed.
    for (name, m) in &files {
        assert_eq!(
            m.get("relations").is_some(),
            name == "intel relations",
            "{name}"
        );
    }
    if let Some((_, m)) = files.iter().find(|(n, _)| n == "intel relations") {
        assert!(m["relations"]["smoother"]["compared"].is_u64(), "{m:#}");
        // A log with scans has the beams' object; its counts add up.
        let b = &m["replay"]["beams"];
        assert_eq!(b["scans"], 910, "{b:#}");
        assert_eq!(b["per_scan"], 30, "{b:#}");
        assert!(b["applied"].as_u64() <= b["chosen"].as_u64(), "{b:#}");
    }
    // A log without scans has none.
    for (name, m) in &files {
        if let Some(r) = m.get("replay")
            && name != "intel relations"
        {
            assert!(r.get("beams").is_none(), "{name}: {r:#}");
            assert_eq!(r["truth_offset_s"], 0.0, "{name}");
        }
    }
    let _ = fs::remove_dir_all(&dir);
}

/// The files of the old shape (a flat object with `ir_readings`,
/// `sim_time_s`, `laps_completed` and `dt_s` in a replay, the smoother's
/// summary under other names, the calibration as unnamed pairs) fail the
/// schema.
#[test]
fn the_old_shape_does_not_validate() {
    let validator = validator();
    for (name, text) in [
        (
            "run",
            include_str!("fixtures/metrics-v1-run.json").to_string(),
        ),
        (
            "monte carlo",
            include_str!("fixtures/metrics-v1-monte-carlo.json").to_string(),
        ),
        (
            "replay",
            include_str!("fixtures/metrics-v1-replay.json").to_string(),
        ),
    ] {
        let old: Value = serde_json::from_str(&text).unwrap();
        assert!(!errors(&validator, &old).is_empty(), "{name}");
        // Even with the new tag it fails.
        let mut tagged = old.clone();
        tagged["schema"] = "locus-metrics/2".into();
        assert!(!errors(&validator, &tagged).is_empty(), "{name}");
    }
    let old: Value = serde_json::from_str(include_str!("fixtures/metrics-v1-replay.json")).unwrap();
    let found = simulator_keys(&old);
    for k in ["/ir_readings", "/sim_time_s", "/laps_completed"] {
        assert!(found.iter().any(|f| f == k), "{k} in {found:?}");
    }
}
