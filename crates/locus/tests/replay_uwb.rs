//! `locus replay librsf` on the Indoor UWB dataset (libRSF's labyrinth
//! run: range-only sightings of four UWB beacons, a ground truth of
//! positions only): it reads and replays with no flags, every range is
//! applied or counted, the heading figures are n/a (null), the NEES is over
//! the 2 position dof, and the position RMSE is reported beside odometry
//! alone's. Its export to Locus CSV v3 replays the same; without its truth
//! the log has no start and the replay says so.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn locus(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(args)
        .output()
        .expect("run locus")
}

fn ok(o: Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).expect("utf-8")
}

fn metrics(out: &Path) -> serde_json::Value {
    serde_json::from_str(&fs::read_to_string(out.join("metrics.json")).expect("metrics.json"))
        .expect("JSON")
}

#[test]
fn the_uwb_log_replays_position_only_and_every_range_is_accounted_for() {
    let input = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/indoor_uwb/Indoor_UWB_Input.txt"
    );
    let text = fs::read_to_string(input).expect("the dataset");
    let ranges = text.lines().filter(|l| l.starts_with("range2 ")).count();
    assert_eq!(ranges, 233);
    let dir = std::env::temp_dir().join(format!("locus-replay-uwb-{}", std::process::id()));
    fs::create_dir_all(&dir).unwrap();
    let path = |name: &str| -> PathBuf { dir.join(name) };
    let s = |p: &Path| p.to_str().expect("utf-8").to_owned();

    let export = path("uwb.csv");
    let out = path("librsf");
    let stdout = ok(locus(&[
        "replay",
        "librsf",
        input,
        "--export",
        &s(&export),
        "--out",
        &s(&out),
        "--no-plots",
    ]));
    let m = metrics(&out);
    // Every range applied, gated or counted as refused, skipped or too late.
    let replay = &m["replay"];
    let counted: u64 = m["counts"]["applied"].as_u64().expect("applied")
        + [
            "gated",
            "not_in_map",
            "unusable",
            "implausible_time",
            "too_late",
            "unknown_sightings",
        ]
        .iter()
        .map(|k| replay[*k].as_u64().expect(k))
        .sum::<u64>();
    assert_eq!(counted, ranges as u64, "{m}");
    assert_eq!(
        m["counts"]["readings"].as_u64().unwrap() + replay["too_late"].as_u64().unwrap(),
        ranges as u64
    );
    let filter = &m["filter"];
    assert!(filter["compared"].as_u64().unwrap() > 400, "{m}");
    // Position only: no heading figure, never 0; the NEES over x and y.
    for key in [
        "heading_rmse_rad",
        "heading_offset_rad",
        "heading_rmse_about_offset_rad",
    ] {
        assert!(filter[key].is_null(), "{key}: {}", filter[key]);
    }
    assert!(m["odometry"]["heading_rmse_rad"].is_null(), "{m}");
    assert_eq!(filter["nees_dof"], 2);
    assert!(filter["mean_nees"].as_f64().unwrap() > 0.0);
    let odometry = m["odometry"]["position_rmse_m"].as_f64().unwrap();
    let filter = filter["position_rmse_m"].as_f64().unwrap();
    assert!(filter.is_finite() && filter > 0.0, "{m}");
    assert!(odometry.is_finite() && odometry > 0.0, "{m}");
    // Issue 27: with no flags, better than odometry alone, and honest: x
    // and y inside the filter's own 3 sigma on >= 90 % of the steps.
    assert!(
        filter < odometry,
        "filter {filter} m, odometry alone {odometry} m"
    );
    let row = stdout
        .lines()
        .find(|l| {
            l.split('┆')
                .next()
                .map(|c| c.trim_start_matches('│').trim())
                == Some("filter")
        })
        .unwrap_or_else(|| panic!("no filter row in\n{stdout}"));
    let shares: Vec<f64> = row
        .split('┆')
        .nth(5)
        .expect("the shares cell")
        .split(['/', '('])
        .filter_map(|v| v.trim().parse().ok())
        .collect();
    assert_eq!(shares.len(), 2, "{row}");
    assert!(shares.iter().all(|s| *s >= 90.0), "{row}");
    assert_eq!(m["replay"]["start"]["from"], "truth_position", "{m}");
    assert!(stdout.contains("odometry alone"), "{stdout}");
    assert!(stdout.contains("mean NEES (2 dof, ideal 2)"), "{stdout}");
    // The 3-sigma share of the heading reads n/a.
    assert!(stdout.contains(" / n/a "), "{stdout}");

    // The export is a v4 log of range lines and truth without heading,
    // and replays to the same figures.
    let csv = fs::read_to_string(&export).unwrap();
    assert!(csv.starts_with("# Locus log v5"), "{csv}");
    assert_eq!(
        csv.lines().filter(|l| l.starts_with("range,")).count(),
        ranges
    );
    assert!(!csv.contains("measurement,"));
    assert!(
        !csv.contains("noise,"),
        "the authors' variance is not the noise"
    );
    let again = path("csv");
    ok(locus(&[
        "replay",
        "csv",
        &s(&export),
        "--out",
        &s(&again),
        "--no-plots",
    ]));
    let m2 = metrics(&again);
    assert_eq!(m2["filter"], m["filter"]);
    assert_eq!(m2["counts"], m["counts"]);

    // Range-only sightings alone, no start, no truth: no initial pose.
    let bare = path("bare.csv");
    let stripped: String = csv
        .lines()
        .filter(|l| !l.starts_with("truth,"))
        .map(|l| format!("{l}\n"))
        .collect();
    fs::write(&bare, stripped).unwrap();
    let o = locus(&[
        "replay",
        "csv",
        &s(&bare),
        "--out",
        &s(&path("bare")),
        "--no-plots",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no initial pose"), "{err}");
    let _ = fs::remove_dir_all(&dir);
}
