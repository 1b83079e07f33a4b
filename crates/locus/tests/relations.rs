//! `locus replay carmen --relations` on the Intel lab (issue 29): the
//! table of the errors against the hand-verified relations (Kuemmerle et
//! al. 2009) and its `metrics.json` section. The corrected poses are the
//! reference the relations were verified against, so their own errors are
//! small; a wrong time alignment (a wrong offset, a scan off by one) or a
//! relation matched to the wrong scan would make them large. Raw odometry's
//! are far larger. The data is read from `../shared/data`; the test is
//! skipped without it.

mod common;

use std::fs;
use std::path::Path;

use serde_json::Value;

/// The cells after the name of the row of the relations' table (in the
/// replay's output `text`) whose name starts with `name`.
fn row(text: &str, name: &str) -> Vec<String> {
    row_after(text, "relations (", name)
}

/// The cells after the name of the first row whose name starts with `name`
/// in the replay's output `text` after `marker`.
fn row_after(text: &str, marker: &str, name: &str) -> Vec<String> {
    let table = &text[text.find(marker).expect("the table's marker")..];
    let line = table
        .lines()
        .find(|l| l.trim_start_matches('│').trim_start().starts_with(name))
        .unwrap_or_else(|| panic!("no row {name} in\n{table}"));
    line.trim_matches('│')
        .split('┆')
        .skip(1)
        .map(|c| c.trim().to_string())
        .collect()
}

/// A row's cell as a number.
fn num(cells: &[String], k: usize) -> f64 {
    cells[k]
        .parse()
        .unwrap_or_else(|e| panic!("{cells:?}[{k}]: {e}"))
}

#[test]
fn the_intel_lab_against_its_relations() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/intel_lab");
    let log = data.join("intel-corrected.log.gz");
    let relations = data.join("intel.relations.xz");
    if !log.is_file() || !relations.is_file() {
        eprintln!("skipped: {} not found", data.display());
        return;
    }
    let dir = common::scratch("relations-intel");
    let s = |p: &Path| p.to_str().expect("utf-8").to_owned();
    common::locus_ok(&["map", "--carmen", &s(&log), "--out", &s(&dir.join("map"))]);
    let (log, map, relations) = (s(&log), s(&dir.join("map/map.yaml")), s(&relations));
    let replay = |out: &str, extra: &[&str]| {
        // The noise as given (not estimated): the relations' figures of
        // the truth and the odometry do not depend on it, and the replay
        // takes a fraction of a second.
        let out = s(&dir.join(out));
        let mut args = vec![
            "replay",
            "carmen",
            &log,
            "--map",
            &map,
            "--relations",
            &relations,
            "--no-estimate",
            "--smooth",
            "--no-plots",
            "--out",
            &out,
        ];
        args.extend_from_slice(extra);
        common::locus_ok(&args)
    };
    let text = replay("replay", &[]);
    println!("{text}");
    assert!(
        text.contains(
            "relations (intel.relations.xz): 2984 in the file; 119 with both ends within 5 ms \
             of a scan's stamp, 14 of them left out as ambiguous"
        ),
        "{text}"
    );
    let deg = 180.0 / core::f64::consts::PI;
    let [filter, smoother, truth, odometry] =
        ["filter", "smoother", "corrected poses", "raw odometry"].map(|name| row(&text, name));
    for cells in [&filter, &smoother, &truth, &odometry] {
        assert_eq!(cells[0], "105", "{cells:?}");
    }
    // The corrected poses: measured 0.036 +- 0.027 m and 0.61 +- 0.86 deg.
    // With the 14 ambiguous relations kept, 0.067 m; with every scan off
    // by one, 0.35 m and 7 deg.
    let (t, r) = (num(&truth, 1), num(&truth, 3));
    assert!(t < 0.05 && r < 1.0, "corrected poses {truth:?}");
    // Raw odometry: measured 3.25 m and 18.5 deg.
    let (ot, or) = (num(&odometry, 1), num(&odometry, 3));
    assert!(ot > 20.0 * t && or > 10.0 * r, "raw odometry {odometry:?}");

    // metrics.json has the same figures, in SI units.
    let metrics: Value =
        serde_json::from_str(&fs::read_to_string(dir.join("replay/metrics.json")).unwrap())
            .unwrap();
    let m = &metrics["relations"];
    assert_eq!(
        [&m["in_file"], &m["on_scans"], &m["ambiguous"]],
        [2984, 119, 14]
    );
    assert_eq!(m["truth"]["compared"], 105);
    let close = |json: &Value, shown: f64, scale: f64, decimals: i32| {
        let v = json.as_f64().expect("a number") * scale;
        (v - shown).abs() <= 0.5 * 10f64.powi(-decimals) + 1e-12
    };
    assert!(close(&m["truth"]["mean_translation_m"], t, 1.0, 3), "{m:#}");
    assert!(close(&m["truth"]["mean_rotation_rad"], r, deg, 2), "{m:#}");
    let spread = num(&odometry, 2);
    assert!(close(&m["odometry"]["std_translation_m"], spread, 1.0, 3));

    // The truth's own error from the relations: measured 0.0170 m in x and
    // y, 0.33 deg (robust, upper bounds). It is a fraction of the
    // relations' mean errors above (each relation joins two poses, and
    // their mean is above their median).
    let e = &m["truth_error"];
    assert_eq!(e["relations"], 105);
    let (sxy, sh) = (
        e["sigma_xy_m"].as_f64().unwrap(),
        e["sigma_heading_rad"].as_f64().unwrap(),
    );
    assert!(sxy > 0.005 && sxy < t, "{e:#}");
    assert!(sh > 0.001 && sh < r / deg, "{e:#}");
    assert!(
        text.contains(&format!(
            "the truth's own error at a pose, from its errors over the 105 relations (robust; \
             all of their disagreement counted as the truth's, so at most): {sxy:.4} m in x and \
             in y, {:.2} deg in heading",
            sh * deg
        )),
        "{text}"
    );
    // The filter's and the smoother's consistency at the 910 scans: the
    // truth's error added to an estimate's covariance can only widen its
    // 3 sigma and shrink its NEES.
    for name in ["filter", "smoother"] {
        let c = &m["consistency"][name];
        assert_eq!(c["compared"], 910, "{c:#}");
        let f = |k: &str| c[k].as_f64().unwrap_or_else(|| panic!("{k} in {c:#}"));
        for axis in ["x", "y", "heading"] {
            let alone = f(&format!("within_3_sigma_{axis}_share"));
            let with = f(&format!("with_truth_error_within_3_sigma_{axis}_share"));
            assert!(alone > 0.0 && with >= alone && with <= 1.0, "{c:#}");
        }
        assert!(f("with_truth_error_mean_nees") < f("mean_nees"), "{c:#}");
        let cells = row_after(&text, "at the scans, against the truth", name);
        assert_eq!(cells[0], "910", "{cells:?}");
    }

    // A wrong offset (the relations' times 0.5 s off the scans'): no
    // relation falls on a scan, and every figure is n/a, not 0.
    let text = replay("wrong-offset", &["--relations-offset", "976052857.837"]);
    assert!(
        text.contains("2984 in the file; 0 with both ends"),
        "{text}"
    );
    let truth = row(&text, "corrected poses");
    assert_eq!(truth, ["0", "n/a", "n/a", "n/a", "n/a"]);
    assert!(
        text.contains("the truth's own error: n/a (fewer than 10 relations judged)"),
        "{text}"
    );
    let _ = fs::remove_dir_all(&dir);
}
