//! Reading a bag against reading the same data from a CSV log (issue 30:
//! "reading a bag costs at most 2x reading the same data from CSV").
//!
//! MRCLAM dataset 6 robot 3 (`../shared/data/mrclam`; 61 158 odometry
//! records, 4 348 sightings, 56 977 truth poses) is written, outside the
//! timing, as a Locus CSV log (`locus_logs::locus_csv::write`) and as a
//! rosbag2-style MCAP bag (the `mcap` crate, zstd chunks as rosbag2 writes
//! them by default, ros2msg schemas, CDR): `/cmd_vel`
//! `geometry_msgs/msg/Twist`, `/landmarks` a sighting type with a header,
//! `/mocap/pose` `geometry_msgs/msg/PoseStamped`. Side by side in group
//! `read_robot3`: `locus_csv::read` of the CSV and
//! `locus_bag::convert::to_locus` of the bag, each giving the same Locus
//! log (checked before timing, times to the nanosecond).
//!
//! Run: `cargo bench -p locus-bag --bench read`; docs/bags.md has the
//! figures.

extern crate alloc;

use alloc::collections::BTreeMap;
use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use locus_bag::mapping::{Landmarks, Mapping, Truth, Velocity};
use locus_logs::locus_csv::{self, LocusLog};

const TWIST: &str = "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n\
================================================================================\n\
MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";
const SIGHTING: &str = "std_msgs/Header header\nuint32 id\nfloat64 range\nfloat64 bearing\n\
================================================================================\n\
MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\
================================================================================\n\
MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";
const POSE: &str = "std_msgs/Header header\ngeometry_msgs/Pose pose\n\
================================================================================\n\
MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\
================================================================================\n\
MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n\
================================================================================\n\
MSG: geometry_msgs/Pose\nPoint position\nQuaternion orientation\n\
================================================================================\n\
MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n\
================================================================================\n\
MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";

/// Little-endian CDR, aligned from the end of the 4-byte header.
struct Cdr(Vec<u8>);

impl Cdr {
    fn new() -> Self {
        Self(vec![0, 1, 0, 0])
    }
    fn align(&mut self, n: usize) {
        while (self.0.len() - 4) % n != 0 {
            self.0.push(0);
        }
    }
    fn f64(&mut self, v: f64) -> &mut Self {
        self.align(8);
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn u32(&mut self, v: u32) -> &mut Self {
        self.align(4);
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    /// A header: the stamp of `t` s and a frame.
    fn header(&mut self, t: f64, frame: &str) -> &mut Self {
        let (sec, ns) = stamp(t);
        #[allow(clippy::cast_sign_loss)]
        self.u32(sec as u32).u32(ns);
        self.u32(u32::try_from(frame.len() + 1).unwrap());
        self.0.extend_from_slice(frame.as_bytes());
        self.0.push(0);
        self
    }
}

/// `t` s as whole seconds and nanoseconds.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
fn stamp(t: f64) -> (i32, u32) {
    let sec = t.floor();
    let ns = ((t - sec) * 1e9).round();
    if ns >= 1e9 {
        (sec as i32 + 1, 0)
    } else {
        (sec as i32, ns as u32)
    }
}

/// `t` to the nanosecond, as a bag gives it back.
fn nanosecond(t: f64) -> f64 {
    let (sec, ns) = stamp(t);
    f64::from(sec) + f64::from(ns) * 1e-9
}

/// The log of robot 3 with its times to the nanosecond.
fn robot3() -> LocusLog {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/mrclam/MRCLAM_Dataset6");
    let dataset = locus_logs::mrclam::Dataset::open(&dir).expect("MRCLAM dataset 6");
    let mut log = locus_replay::Log::mrclam(&dataset, 3).unwrap().to_locus();
    for o in &mut log.odometry {
        o.time = nanosecond(o.time);
    }
    for m in &mut log.measurements {
        m.time = nanosecond(m.time);
    }
    let poses = log
        .truth
        .poses()
        .iter()
        .map(|p| locus_logs::mrclam::TruthPose {
            time: nanosecond(p.time),
            ..*p
        })
        .collect();
    log.truth = locus_logs::mrclam::Groundtruth::new(poses).unwrap();
    log.start = None;
    log
}

/// `log` written as a bag at `path`.
fn write_bag(log: &LocusLog, path: &Path) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::Writer::new(file).unwrap();
    let mut channel = |name: &str, topic: &str, text: &str| {
        let schema = w.add_schema(name, "ros2msg", text.as_bytes()).unwrap();
        w.add_channel(schema, topic, "cdr", &BTreeMap::new())
            .unwrap()
    };
    let (cmd, sight, pose) = (
        channel("geometry_msgs/msg/Twist", "/cmd_vel", TWIST),
        channel("locus_msgs/msg/LandmarkSighting", "/landmarks", SIGHTING),
        channel("geometry_msgs/msg/PoseStamped", "/mocap/pose", POSE),
    );
    let mut write = |channel_id: u16, t: f64, data: &[u8]| {
        let (sec, ns) = stamp(t);
        #[allow(clippy::cast_sign_loss)]
        let time = sec as u64 * 1_000_000_000 + u64::from(ns);
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: 0,
            log_time: time,
            publish_time: time,
        };
        w.write_to_known_channel(&header, data).unwrap();
    };
    for o in &log.odometry {
        let mut c = Cdr::new();
        c.f64(o.v).f64(0.0).f64(0.0).f64(0.0).f64(0.0).f64(o.omega);
        write(cmd, o.time, &c.0);
    }
    for m in &log.measurements {
        let mut c = Cdr::new();
        c.header(m.time, "base_link")
            .u32(m.id)
            .f64(m.range)
            .f64(m.bearing.unwrap());
        write(sight, m.time, &c.0);
    }
    for p in log.truth.poses() {
        let (s, co) = (p.theta / 2.0).sin_cos();
        let mut c = Cdr::new();
        c.header(p.time, "world").f64(p.x).f64(p.y).f64(0.0);
        c.f64(0.0).f64(0.0).f64(s).f64(co);
        write(pose, p.time, &c.0);
    }
    w.finish().unwrap();
}

fn mapping(log: &LocusLog) -> Mapping {
    Mapping {
        base_frame: "base_link".into(),
        velocity: Velocity {
            topic: "/cmd_vel".into(),
            linear: None,
            angular: None,
            stamp: None,
        },
        landmarks: Some(Landmarks {
            topic: "/landmarks".into(),
            list: None,
            id: "id".into(),
            range: "range".into(),
            bearing: "bearing".into(),
            stamp: None,
            frame: None,
        }),
        truth: Some(Truth {
            topic: "/mocap/pose".into(),
            position: None,
            orientation: None,
            stamp: None,
        }),
        landmark_map: log
            .landmarks
            .iter()
            .map(|l| locus_bag::mapping::MapEntry {
                id: l.id,
                x: l.x,
                y: l.y,
            })
            .collect(),
        map: None,
        walls: Vec::new(),
        scans: Vec::new(),
        ranges: Vec::new(),
    }
}

fn bench(c: &mut Criterion) {
    let log = robot3();
    let dir = std::env::temp_dir().join(format!("locus-bench-bag-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (csv, bag) = (dir.join("robot3.csv"), dir.join("robot3.mcap"));
    std::fs::write(&csv, locus_csv::write(&log)).unwrap();
    write_bag(&log, &bag);
    let mapping = mapping(&log);
    let from_bag = locus_bag::convert::to_locus(&bag, &mapping, "mapping").unwrap();
    let from_csv = locus_csv::read(&csv).unwrap();
    assert_eq!(from_bag.odometry, from_csv.odometry);
    assert_eq!(from_bag.measurements, from_csv.measurements);
    assert_eq!(from_bag.landmarks, from_csv.landmarks);
    assert_eq!(from_bag.truth.poses().len(), from_csv.truth.poses().len());
    println!(
        "robot 3: {} odometry records, {} sightings, {} truth poses; CSV {} bytes, bag {} bytes",
        log.odometry.len(),
        log.measurements.len(),
        log.truth.poses().len(),
        std::fs::metadata(&csv).unwrap().len(),
        std::fs::metadata(&bag).unwrap().len()
    );
    let mut g = c.benchmark_group("read_robot3");
    g.sample_size(20);
    g.bench_function("csv", |b| b.iter(|| locus_csv::read(&csv).unwrap()));
    g.bench_function("bag", |b| {
        b.iter(|| locus_bag::convert::to_locus(&bag, &mapping, "mapping").unwrap());
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
