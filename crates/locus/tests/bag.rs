//! `locus replay bag` (issue 30): logs exported as Locus CSV logs
//! (`locus replay ... --export`) are written as rosbag2 MCAP bags by the
//! `rosbags` Python package (an independent writer:
//! `scripts/locus_csv_to_bag.py`), and each bag replays as its CSV log:
//!
//! * MRCLAM dataset 6 robot 3, with a sensor mount added: Twist
//!   velocities, custom landmark sightings with their schema, the mount in
//!   `/tf_static`, a mocap `PoseStamped`; no flags. Measured: estimates
//!   identical to the bit (asserted to 1e-9), truth headings to 4.4e-16
//!   rad (the quaternion's round trip).
//! * laser_wall_1d: paper 000's laser as `sensor_msgs/msg/Range`, the wall
//!   in the mapping. Measured: identical.
//! * The Intel lab: its 180-beam scans as `sensor_msgs/msg/LaserScan`, the
//!   map file named in the mapping, the noise given. Measured: identical.
//!
//! A bag's times have nanosecond resolution and a scan's angles and range
//! limits are `float32`: the CSV logs are first given their times to the
//! nanosecond and their beam geometry in `float32`, so that both carry
//! the same numbers. A mapping naming a field the messages do not have, or
//! a topic the bag does not have, fails with the topic and the field.
//! `--list` lists the topics and proposes a mapping. Python comes from `LOCUS_PYTHON`, else `python3`, with rosbags
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

/// `text` (a Locus CSV log) with each time to the nanosecond (as a bag
/// stamps it: `sec + nanosec 1e-9`) and each beam sensor's range limits and
/// angles in `float32` (as a `LaserScan` carries them); no `start` line.
fn as_a_bag_carries_it(text: &str) -> String {
    let nanosecond = |t: f64| {
        let mut sec = t.floor();
        let mut ns = ((t - sec) * 1e9).round();
        if ns >= 1e9 {
            sec += 1.0;
            ns -= 1e9;
        }
        sec + ns * 1e-9
    };
    let mut out = String::new();
    for line in text.lines() {
        let mut f: Vec<String> = line.split(',').map(str::to_string).collect();
        match f[0].as_str() {
            "start" => continue,
            "odometry" | "measurement" | "range" | "truth" | "scan" => {
                f[1] = nanosecond(f[1].parse().unwrap()).to_string();
            }
            "beam_sensor" => {
                for v in &mut f[5..9] {
                    #[allow(clippy::cast_possible_truncation)]
                    let single = v.parse::<f64>().unwrap() as f32;
                    *v = f64::from(single).to_string();
                }
            }
            _ => {}
        }
        out.push_str(&f.join(","));
        out.push('\n');
    }
    out
}

/// The bag `scripts/locus_csv_to_bag.py` writes of the CSV log `csv`, and
/// its mapping.
fn to_bag(csv: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let python = std::env::var("LOCUS_PYTHON").unwrap_or_else(|_| "python3".to_owned());
    let stem = csv.file_stem().unwrap().to_str().unwrap();
    let bag_dir = csv.with_file_name(format!("{stem}-bag"));
    let mapping = csv.with_file_name(format!("{stem}.toml"));
    let out = Command::new(&python)
        .arg(root.join("scripts/locus_csv_to_bag.py"))
        .args([csv, &bag_dir, &mapping])
        .output()
        .unwrap_or_else(|e| panic!("cannot run {python}: {e}"));
    assert!(
        out.status.success(),
        "scripts/locus_csv_to_bag.py failed (is rosbags installed? scripts/test.sh installs it):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (bag_dir.join(format!("{stem}-bag.mcap")), mapping)
}

/// The largest differences between two replays' `log.csv` files in
/// `names` (asserting they have the same rows).
fn differences(a: &Path, b: &Path, names: &[&str]) -> Vec<f64> {
    let (a, b) = (columns(a, names), columns(b, names));
    assert_eq!(a.len(), b.len());
    let mut worst = vec![0.0f64; names.len()];
    for (ra, rb) in a.iter().zip(&b) {
        for k in 0..names.len() {
            if ra[k].is_finite() || rb[k].is_finite() {
                worst[k] = worst[k].max((ra[k] - rb[k]).abs());
            }
        }
    }
    worst
}

const ESTIMATES: [&str; 7] = [
    "time_s",
    "x_m",
    "y_m",
    "theta_rad",
    "var_x_m2",
    "var_y_m2",
    "var_theta_rad2",
];

/// Replays `args` (after `replay`) to `dir/out` with no plots.
fn replay(dir: &Path, args: &[&str], out: &str) -> String {
    let mut all = vec!["replay"];
    all.extend_from_slice(args);
    let out = dir.join(out);
    let out = out.to_str().unwrap();
    all.extend_from_slice(&["--no-plots", "--out", out]);
    common::locus_ok(&all)
}

/// Replays the bag `bag` with its `mapping` and the CSV log `csv` alike
/// (with `flags`, to `dir/NAME-bag` and `dir/NAME-csv`) and asserts their
/// estimates agree to 1e-9.
fn bag_as_its_csv(
    dir: &Path,
    (bag, mapping, csv): (&Path, &Path, &Path),
    flags: &[&str],
    name: &str,
) {
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let (bag, mapping, csv) = (s(bag), s(mapping), s(csv));
    let (to_bag, to_csv) = (format!("{name}-bag"), format!("{name}-csv"));
    let said = replay(
        dir,
        &[
            &["bag", bag.as_str(), "--topics", mapping.as_str()][..],
            flags,
        ]
        .concat(),
        &to_bag,
    );
    assert!(said.contains("scans / beams in them"), "{said}");
    replay(dir, &[&["csv", csv.as_str()][..], flags].concat(), &to_csv);
    let d = differences(
        &dir.join(to_bag).join("log.csv"),
        &dir.join(to_csv).join("log.csv"),
        &ESTIMATES,
    );
    println!("{name}: largest differences {ESTIMATES:?}: {d:?}");
    assert!(d.iter().all(|&v| v <= 1e-9), "{d:?}");
}

#[test]
fn bags_of_ranges_and_of_scans_replay_as_their_csv() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if !data.join("laser_wall_1d").is_dir() || !data.join("intel_lab").is_dir() {
        eprintln!("skipped: {} not found", data.display());
        return;
    }
    let dir = common::scratch("bag-beams");
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    // Paper 000's laser to a wall as sensor_msgs/msg/Range; the noise
    // given (the search is another test's), the start given (a bag has no
    // start record).
    let exported = dir.join("export.csv");
    replay(
        &dir,
        &[
            "laser-wall",
            &s(&data.join("laser_wall_1d/dataset1.txt")),
            "--export",
            &s(&exported),
        ],
        "laser-wall",
    );
    let csv = dir.join("wall.csv");
    std::fs::write(
        &csv,
        as_a_bag_carries_it(&std::fs::read_to_string(&exported).unwrap()),
    )
    .unwrap();
    let (bag, mapping) = to_bag(&csv);
    let mapping_text = std::fs::read_to_string(&mapping).unwrap();
    assert!(
        mapping_text.contains("[[range]]\ntopic = \"/range0\"")
            && mapping_text.contains("[[wall]]"),
        "{mapping_text}"
    );
    let flags = [
        "--q-v",
        "1e-4",
        "--q-omega",
        "1e-4",
        "--sigma-beam",
        "0.01",
        "--no-estimate",
        "--start",
        "0.9844566829712001,0,0",
    ];
    bag_as_its_csv(&dir, (&bag, &mapping, &csv), &flags, "wall");

    // The Intel lab's scans as sensor_msgs/msg/LaserScan, against its map.
    let map_dir = dir.join("intel-map");
    let carmen = s(&data.join("intel_lab/intel-corrected.log.gz"));
    common::locus_ok(&["map", "--carmen", &carmen, "--out", &s(&map_dir)]);
    let noise = [
        "--q-v",
        "0.00902",
        "--q-omega",
        "0.002",
        "--sigma-beam",
        "0.04691",
        "--beam-bias-sigma",
        "0.06473",
        "--beam-bias-tau",
        "28.75",
        "--odometry-delay",
        "0.1",
        "--no-estimate",
    ];
    let exported = dir.join("intel-export.csv");
    let map = s(&map_dir.join("map.yaml"));
    let export = s(&exported);
    replay(
        &dir,
        &[
            &[
                "carmen",
                carmen.as_str(),
                "--map",
                map.as_str(),
                "--export",
                export.as_str(),
            ][..],
            &noise,
        ]
        .concat(),
        "intel",
    );
    let text = as_a_bag_carries_it(&std::fs::read_to_string(&exported).unwrap());
    let csv = dir.join("intel.csv");
    std::fs::write(&csv, format!("map,{map}\n{text}")).unwrap();
    let (bag, mapping) = to_bag(&csv);
    bag_as_its_csv(&dir, (&bag, &mapping, &csv), &noise, "intel");
    let _ = std::fs::remove_dir_all(&dir);
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
    let (bag, mapping) = to_bag(&csv);

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

    let said = replay(
        &dir,
        &["bag", &s(&bag), "--topics", &s(&mapping)],
        "from-bag",
    );
    assert!(said.contains("65506 events"), "{said}");
    replay(&dir, &["csv", &s(&csv)], "from-csv");
    let d = differences(
        &dir.join("from-bag/log.csv"),
        &dir.join("from-csv/log.csv"),
        &ESTIMATES,
    );
    assert_eq!(d[0], 0.0, "times");
    assert!(d[1..].iter().all(|&v| v <= 1e-9), "{d:?}");
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
