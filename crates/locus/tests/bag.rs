//! `locus replay bag` (issue 30): MRCLAM dataset 6 robot 3, exported as a
//! Locus CSV log (`locus replay mrclam --export`, with a sensor mount
//! added), is written as a rosbag2 MCAP bag by the `rosbags` Python package
//! (an independent writer: `scripts/locus_csv_to_bag.py`; Twist velocities,
//! custom landmark sightings with their schema, the mount in `/tf_static`,
//! a mocap `PoseStamped`). Replayed with no flags, the bag gives the CSV
//! replay's estimates (measured: identical to the bit; asserted to 1e-9),
//! and its truth to the quaternion's rounding. A mapping naming a field
//! the messages do not have, or a topic the bag does not have, fails with
//! the topic and the field. `--list` lists the topics and proposes a
//! mapping. Python comes from `LOCUS_PYTHON`, else `python3`, with rosbags
//! installed (scripts/test.sh installs scripts/requirements-crosscheck.txt);
//! the data is read from `../shared/data` (skipped without it).

mod common;

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

/// The columns `names` of a replay's `log.csv`, row by row.
fn columns(path: &Path, names: &[&str]) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at: Vec<usize> = names
        .iter()
        .map(|n| {
            header
                .iter()
                .position(|h| h == n)
                .unwrap_or_else(|| panic!("{n}"))
        })
        .collect();
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            at.iter()
                .map(|&i| f[i].parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

#[test]
fn a_bag_written_by_rosbags_replays_as_its_csv() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dataset = root.join("../shared/data/mrclam/MRCLAM_Dataset6");
    if !dataset.is_dir() {
        eprintln!("skipped: {} not found", dataset.display());
        return;
    }
    let dir = common::scratch("bag");
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let exported = dir.join("robot3.csv");
    common::locus_ok(&[
        "replay",
        "mrclam",
        &s(&dataset),
        "--robot",
        "3",
        "--export",
        &s(&exported),
        "--no-plots",
        "--out",
        &s(&dir.join("mrclam")),
    ]);
    // A camera 5 cm ahead, 1 cm left, turned 0.02 rad: the bag says so in
    // /tf_static.
    let text = std::fs::read_to_string(&exported).unwrap();
    let csv = dir.join("robot3-mounted.csv");
    let first_landmark = text.find("\nlandmark,").unwrap() + 1;
    std::fs::write(
        &csv,
        format!(
            "{}sensor,0.05,0.01,0.02\n{}",
            &text[..first_landmark],
            &text[first_landmark..]
        ),
    )
    .unwrap();
    let python = std::env::var("LOCUS_PYTHON").unwrap_or_else(|_| "python3".to_owned());
    let (bag_dir, mapping) = (dir.join("robot3-bag"), dir.join("robot3.toml"));
    let out = Command::new(&python)
        .arg(root.join("scripts/locus_csv_to_bag.py"))
        .args([&csv, &bag_dir, &mapping])
        .output()
        .unwrap_or_else(|e| panic!("cannot run {python}: {e}"));
    assert!(
        out.status.success(),
        "scripts/locus_csv_to_bag.py failed (is rosbags installed? scripts/test.sh installs it):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bag = bag_dir.join("robot3-bag.mcap");

    let listed = common::locus_ok(&["replay", "bag", &s(&bag), "--list"]);
    for row in [
        ("/cmd_vel", "geometry_msgs/msg/Twist", "61158"),
        ("/landmarks", "locus_msgs/msg/LandmarkSighting", "4348"),
        ("/tf_static", "tf2_msgs/msg/TFMessage", "1"),
        ("/mocap/pose", "geometry_msgs/msg/PoseStamped", "56977"),
    ] {
        let line = listed
            .lines()
            .find(|l| l.contains(&format!("│ {} ", row.0)))
            .unwrap_or_else(|| panic!("{listed}"));
        assert!(line.contains(row.1) && line.contains(row.2), "{line}");
    }
    assert!(
        listed.contains("[velocity]\ntopic = \"/cmd_vel\""),
        "{listed}"
    );
    assert!(
        listed.contains("[truth]\ntopic = \"/mocap/pose\""),
        "{listed}"
    );
    assert!(
        listed.contains("[landmarks]\ntopic = \"/landmarks\""),
        "{listed}"
    );

    let replay = |args: &[&str], out: &str| {
        let mut all = vec!["replay"];
        all.extend_from_slice(args);
        let out = s(&dir.join(out));
        all.extend_from_slice(&["--no-plots", "--out", &out]);
        common::locus_ok(&all)
    };
    let said = replay(&["bag", &s(&bag), "--topics", &s(&mapping)], "from-bag");
    assert!(said.contains("65506 events"), "{said}");
    replay(&["csv", &s(&csv)], "from-csv");
    let names = [
        "time_s",
        "x_m",
        "y_m",
        "theta_rad",
        "var_x_m2",
        "var_y_m2",
        "var_theta_rad2",
    ];
    let a = columns(&dir.join("from-bag/log.csv"), &names);
    let b = columns(&dir.join("from-csv/log.csv"), &names);
    assert_eq!(a.len(), b.len());
    let mut worst = [0.0f64; 7];
    for (ra, rb) in a.iter().zip(&b) {
        for k in 0..7 {
            worst[k] = worst[k].max((ra[k] - rb[k]).abs());
        }
    }
    assert_eq!(worst[0], 0.0, "times");
    assert!(worst[1..].iter().all(|&d| d <= 1e-9), "{worst:?}");
    let truth = ["true_x_m", "true_y_m", "true_theta_rad"];
    let (ta, tb) = (
        columns(&dir.join("from-bag/log.csv"), &truth),
        columns(&dir.join("from-csv/log.csv"), &truth),
    );
    let heading = ta
        .iter()
        .zip(&tb)
        .filter(|(x, _)| x[2].is_finite())
        .map(|(x, y)| (x[2] - y[2]).abs())
        .fold(0.0f64, f64::max);
    assert!(heading < 1e-12, "{heading}");

    // A wrong mapping: a field the messages do not have, a topic the bag
    // does not have, a key the mapping does not know.
    let wrong = |name: &str, text: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        common::fails_within(
            &[
                "replay",
                "bag",
                &s(&bag),
                "--topics",
                &s(&path),
                "--no-plots",
            ],
            60.0,
        )
    };
    let e = wrong(
        "field.toml",
        "[velocity]\ntopic = \"/cmd_vel\"\nlinear = \"linear.q\"\n",
    );
    assert!(
        e.contains("topic /cmd_vel (geometry_msgs/msg/Twist), field linear.q: no such field"),
        "{e}"
    );
    let e = wrong("topic.toml", "[velocity]\ntopic = \"/odom\"\n");
    assert!(
        e.contains("velocity.topic: topic /odom is not in the bag"),
        "{e}"
    );
    let e = wrong(
        "key.toml",
        "[velocity]\ntopic = \"/cmd_vel\"\nspeed = \"x\"\n",
    );
    assert!(e.contains("key.toml:3") && e.contains("speed"), "{e}");
    let e = wrong(
        "landmarks.toml",
        "[velocity]\ntopic = \"/cmd_vel\"\n[landmarks]\ntopic = \"/landmarks\"\nrange = \"distance\"\n",
    );
    assert!(
        e.contains("topic /landmarks (locus_msgs/msg/LandmarkSighting), field distance"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--list` on the bag rosbag2 wrote: its two topics, decodable, and no
/// velocity topic to propose.
#[test]
fn a_rosbag2_bag_is_listed() {
    let bag = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/rosbag2_cdr_test/cdr_test_0.mcap");
    if !bag.is_file() {
        eprintln!("skipped: {} not found", bag.display());
        return;
    }
    let listed = common::locus_ok(&["replay", "bag", bag.to_str().unwrap(), "--list"]);
    assert!(listed.contains("2 topics, 7 messages"), "{listed}");
    let rows: HashMap<&str, &str> = listed
        .lines()
        .filter_map(|l| {
            let l = l.trim_start_matches('│').trim_start();
            l.split_once(' ')
        })
        .collect();
    assert!(
        rows["/test_topic"].contains("test_msgs/msg/BasicTypes"),
        "{listed}"
    );
    assert!(rows["/array_topic"].contains("┆ 4 "), "{listed}");
    assert!(listed.contains("no velocity topic found"), "{listed}");
}
