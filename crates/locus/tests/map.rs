//! `locus map`: a grid mapped from a synthetic log (exact ranges in a
//! square room, truth with heading) casts as the room's walls do; the
//! Intel lab maps from its corrected poses to a grid of the lab's size.

mod common;

use core::f64::consts::{PI, TAU};
use core::fmt::Write as _;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use locus_map::{Map, Segment, SegmentMap};

/// Runs `locus map` with `args`, asserts success and returns the standard
/// output.
fn map(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_locus"))
        .arg("map")
        .args(args)
        .output()
        .expect("run locus map");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "locus map {args:?} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// The value cell of the summary row whose name starts with `name`.
fn row<'a>(table: &'a str, name: &str) -> &'a str {
    table
        .lines()
        .find(|l| l.trim_start_matches('│').trim_start().starts_with(name))
        .and_then(|l| l.split('┆').nth(1))
        .map_or_else(
            || panic!("no row {name} in\n{table}"),
            |v| v.trim_end_matches('│').trim(),
        )
}

/// Side of the square room, m.
const SIDE: f64 = 8.0;
/// The sensor's range limit, m.
const MAX_RANGE: f64 = 7.0;
/// The sensor's forward offset on the robot, m.
const MOUNT_X: f64 = 0.1;
/// Beams of the sensor.
const BEAMS: u32 = 90;

fn room() -> SegmentMap {
    let c = [[0.0, 0.0], [SIDE, 0.0], [SIDE, SIDE], [0.0, SIDE]];
    SegmentMap::new((0..4).map(|k| Segment::new(c[k], c[(k + 1) % 4])).collect()).unwrap()
}

/// A robot on a circle of radius 2.5 m about the room's centre (0.5 m/s),
/// heading along it, for 40 s: truth at 50 Hz, a 90-beam scan at 5 Hz
/// with exact ranges, and one scan after the truth ends (skipped).
fn room_log(walls: &SegmentMap) -> String {
    let step = TAU / f64::from(BEAMS);
    let mut s = format!(
        "# Locus log v4\nbeam_sensor,0,{MOUNT_X},0,0,0.05,{MAX_RANGE},{},{step},{BEAMS}\n",
        -PI
    );
    let (r, v) = (2.5, 0.5);
    let pose = |t: f64| {
        let a = v / r * t;
        [
            SIDE / 2.0 + r * a.cos(),
            SIDE / 2.0 + r * a.sin(),
            (a + PI / 2.0 + PI).rem_euclid(TAU) - PI,
        ]
    };
    for i in 0..=2000 {
        let t = f64::from(i) * 0.02;
        let p = pose(t);
        writeln!(s, "truth,{t:.2},{:.9},{:.9},{:.9}", p[0], p[1], p[2]).unwrap();
        if i % 10 == 5 || i == 2000 {
            let t_scan = if i == 2000 { t + 1.0 } else { t };
            let origin = [p[0] + MOUNT_X * p[2].cos(), p[1] + MOUNT_X * p[2].sin()];
            write!(s, "scan,{t_scan:.2},0").unwrap();
            for k in 0..BEAMS {
                let a = p[2] - PI + f64::from(k) * step;
                match walls.cast(origin, a, MAX_RANGE) {
                    Some(h) if h.range < MAX_RANGE => write!(s, ",{:.6}", h.range).unwrap(),
                    _ => s.push_str(",max"),
                }
            }
            s.push('\n');
        }
    }
    s
}

#[test]
fn a_room_mapped_from_exact_scans_casts_as_its_walls() {
    let walls = room();
    let dir = common::scratch("map-room");
    let log = dir.join("room.csv");
    std::fs::write(&log, room_log(&walls)).unwrap();
    let out = dir.join("out");
    let table = map(&[
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--resolution",
        "0.05",
        "--margin",
        "0.5",
    ]);
    println!("{table}");
    assert_eq!(row(&table, "scans used"), "200");
    assert_eq!(row(&table, "scans skipped"), "1");
    for f in ["map.yaml", "map.pgm", "map.png"] {
        assert!(out.join(f).is_file(), "{f} not written");
    }
    let Map::Grid(grid) = Map::load(&out.join("map.yaml")).unwrap() else {
        panic!("map.yaml is not a grid");
    };
    // A grid hit agrees if its point lies within two cells of a wall (its
    // range may differ more at grazing incidence, by 1 / cos).
    let cell = grid.geometry().resolution();
    let off_wall = |p: [f64; 2]| {
        [p[0], SIDE - p[0], p[1], SIDE - p[1]]
            .into_iter()
            .map(f64::abs)
            .fold(f64::INFINITY, f64::min)
    };
    let (mut n, mut near, mut worst, mut worst_range) = (0, 0, 0.0_f64, 0.0_f64);
    let mut others = Vec::new();
    for origin in [[4.0, 4.0], [2.0, 5.5], [5.5, 2.5], [3.0, 3.0], [6.0, 6.2]] {
        for k in 0..72 {
            let a = f64::from(k) * TAU / 72.0 + 0.01;
            let exact = walls.cast(origin, a, f64::INFINITY).unwrap().range;
            n += 1;
            match grid.cast(origin, a, f64::INFINITY) {
                Some(h) if off_wall(h.point) <= 2.0 * cell => {
                    near += 1;
                    worst = worst.max(off_wall(h.point));
                    worst_range = worst_range.max((h.range - exact).abs());
                }
                h => others.push((origin, a, h.map(|h| h.point))),
            }
        }
    }
    println!(
        "{near} of {n} grid casts hit within two cells of a wall (farthest {worst:.3} m; \
         range differences up to {worst_range:.3} m); the others: {others:?}"
    );
    assert!(near * 100 >= n * 99, "{near} of {n} within two cells");
}

#[test]
fn the_intel_lab_maps_from_its_corrected_poses() {
    let log = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/intel_lab/intel-corrected.log.gz");
    if !log.is_file() {
        eprintln!("skipped: {} not found", log.display());
        return;
    }
    let out = common::scratch("map-intel");
    let start = Instant::now();
    let table = map(&[
        "--carmen",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let seconds = start.elapsed().as_secs_f64();
    println!("{table}\nmapped in {seconds:.2} s");
    assert_eq!(row(&table, "scans used"), "910");
    assert_eq!(row(&table, "scans skipped"), "0");
    let Map::Grid(grid) = Map::load(&out.join("map.yaml")).unwrap() else {
        panic!("map.yaml is not a grid");
    };
    let g = grid.geometry();
    let size = [g.width(), g.height()].map(|c| c as f64 * g.resolution());
    let (occupied, free, unknown) = grid.counts();
    println!(
        "grid {:.1} x {:.1} m; cells occupied {occupied}, free {free}, unknown {unknown}",
        size[0], size[1]
    );
    // The lab is about 30 m square; stray long returns widen the box a
    // little.
    assert!(
        size.iter().all(|&s| (28.0..=50.0).contains(&s)),
        "{size:?} m"
    );
    // Walls about 0.05 m thick: of the order of (perimeter of rooms and
    // corridors) / cell, a few thousand to a few tens of thousands.
    assert!((3_000..=40_000).contains(&occupied), "{occupied} occupied");
    assert!(free > 5 * occupied, "{free} free, {occupied} occupied");
}
