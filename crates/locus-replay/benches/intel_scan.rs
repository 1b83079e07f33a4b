//! Speed of a scan's correction on the Intel lab (issue 29, "Speed"). The
//! lab's CARMEN log (`../shared/data/intel_lab/intel-corrected.log.gz`:
//! 910 scans of 180 beams, raw odometry between them) is read with
//! `locus_logs::carmen` as `locus replay carmen` reads it, and its map
//! built from the corrected scans as `locus map --carmen` builds it (the
//! same bounds, 0.05 m cells, 1 m margin, `BuilderConfig::default()`),
//! written in ROS map_server's format to a temporary directory and loaded
//! back as `--map` loads it; all of it outside the timing.
//!
//! Side by side in one run, group `intel_replay`: [`locus_replay::replay`]
//! of the whole log, filter only (no smoother; the noise given, so nothing
//! is estimated), with every beam of every scan (`Beams::per_scan` 180),
//! with the default 30 beams, and the same log with its scans removed
//! (odometry only). `(180 beams - odometry only) / scans` is the time of
//! one full scan's correction, casts and updates included; the log's
//! duration over a replay's time is its real-time factor.
//!
//! Then, group `intel_scan_180`, one scan per iteration at the scans'
//! corrected poses in turn, the beam loop of the replay's `filter.rs` on
//! a scan it could not align, through the replay's own functions
//! (`locus_replay::beam`: the cast from the sensor, the plane linearised
//! at the estimate, the short-reading test; then the running filter's
//! Student-t correction behind the 99 % gate, no recovery) to split a
//! scan's time: the casts alone (the beams with a return), the updates
//! alone (the planes cast beforehand), and both.
//!
//! Run: `cargo bench -p locus-replay --bench intel_scan`. The setup prints
//! the log's figures (scans, duration, median time between scans) and what
//! the beams did in each replay; docs/replay.md ("Walls and beams",
//! "Speed") has the figures.

use core::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use locus_core::nalgebra::{SMatrix, SVector};
use locus_core::{Belief, ChiSquareGate, Ekf, Rules, StudentT, Track, Update};
use locus_logs::BeamSensor;
use locus_logs::scans::Reading as Stored;
use locus_map::{BuilderConfig, GridBuilder, GridGeometry, Map, Reading};
use locus_models::calibrated_unicycle::{RANGE_BIAS, V_SCALE};
use locus_models::planar_beam::PlanarBeam;
use locus_replay::beam::{self, Beam};
use locus_replay::log::{Scans, SharedMap};
use locus_replay::{Beams, Config, Log, STATE, replay};

fn log_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/intel_lab/intel-corrected.log.gz")
}

/// The grid `locus map --carmen` makes from the corrected scans, through
/// its ROS files (written to and read back from `dir`).
fn intel_map(sensor: &BeamSensor, scans: &Scans, poses: &[[f64; 3]], dir: &Path) -> Map {
    let placed = || {
        scans
            .iter()
            .zip(poses)
            .map(|(scan, &p)| (sensor.mounted(p), scan.ranges))
    };
    let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut add = |p: [f64; 2]| {
        for k in 0..2 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    };
    for (pose, ranges) in placed() {
        add([pose[0], pose[1]]);
        for (k, &r) in (0u32..).zip(ranges) {
            if let Stored::Range(r) = Stored::of(r) {
                let a = pose[2] + sensor.angle(k);
                let r = f64::from(r);
                add([pose[0] + r * a.cos(), pose[1] + r * a.sin()]);
            }
        }
    }
    let geometry = GridGeometry::covering(min, max, 1.0, 0.05).expect("the grid's size");
    let mut builder = GridBuilder::new(geometry, BuilderConfig::default()).expect("builder");
    for (pose, ranges) in placed() {
        for (k, &r) in (0u32..).zip(ranges) {
            let reading = match Stored::of(r) {
                Stored::Range(r) => Reading::Range(f64::from(r)),
                Stored::NoReturn => Reading::NoReturn,
                Stored::Missing => continue,
            };
            builder.insert_beam([pose[0], pose[1]], pose[2] + sensor.angle(k), reading);
        }
    }
    let yaml = dir.join("map.yaml");
    locus_map::ros::save(&builder.finish(), &yaml, locus_map::ros::Mode::Trinary)
        .expect("writing the map");
    Map::load(&yaml).expect("reading the map back")
}

/// The replay's settings: the command's defaults, the noise given.
fn config(per_scan: u32) -> Config {
    Config {
        q_v: 0.01,
        q_omega: 0.01,
        beams: Beams {
            per_scan,
            sigma: 0.05,
            ..Beams::default()
        },
        ..Config::default()
    }
}

/// One replay of `log` (the sink keeps the last position, so nothing is
/// optimised away).
fn run(log: &Log, cfg: &Config) -> (usize, f64) {
    let mut last = 0.0;
    let report = replay(black_box(log), cfg, |s| last = s.belief.x[0]).expect("replay");
    (report.steps, last)
}

/// What one beam's update did.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Did {
    /// No plane from the estimate, or read far short of it: skipped.
    Skipped,
    /// Applied at full weight.
    Applied,
    /// Applied with a Student-t weight below 1 (corrected twice).
    DownWeighted,
    /// Rejected by the gate, or refused.
    Gated,
}

/// The replay's beam loop (`filter.rs`, `scan_correct`, on a scan it
/// could not align) through the functions it calls
/// ([`locus_replay::beam`]), for one scan at a time.
struct Replica<'a> {
    map: &'a Map,
    sensor: BeamSensor,
    beams: Beams,
    /// The replay's rules for beams: its gate, no recovery.
    rules: Rules<f64>,
    robust: StudentT<f64>,
}

impl Replica<'_> {
    /// Beam `k`'s plane at the state `x`; `None` where the cast meets
    /// nothing usable.
    fn plane(&self, k: usize, x: &SVector<f64, STATE>) -> Option<PlanarBeam<f64>> {
        beam::beam_model(self.map, &self.sensor, k, x, &self.beams)
    }

    /// One beam's correction after it was judged.
    fn correct(&self, track: &mut Track<f64, STATE>, judged: Beam, z: f64) -> Did {
        let Beam::Usable { model, .. } = judged else {
            return Did::Skipped;
        };
        let z = SVector::<f64, 1>::new(z);
        match track.correct_robust(&self.rules, &self.robust, &model, &z) {
            Ok(Update::Applied { weight, .. }) if weight < 1.0 => Did::DownWeighted,
            Ok(Update::Applied { .. }) => Did::Applied,
            _ => Did::Gated,
        }
    }

    /// One beam's update against the plane `model` it met: judged at the
    /// estimate (linearised, the short-reading test), then the Student-t
    /// correction behind the gate.
    fn update(&self, track: &mut Track<f64, STATE>, model: &PlanarBeam<f64>, z: f64) -> Did {
        let x = track.belief.x;
        let judged = beam::judge(model, z, &x, &x, &track.belief.p, &self.beams);
        self.correct(track, judged, z)
    }

    /// A scan's beams with a return, each cast from the estimate the one
    /// before left, then updated; `did` told what each did.
    fn scan(&self, track: &mut Track<f64, STATE>, ranges: &[f32], mut did: impl FnMut(Did)) {
        for (k, &r) in ranges.iter().enumerate() {
            let Some(z) = range(r) else { continue };
            let x = *black_box(&track.belief.x);
            let p = &track.belief.p;
            let judged = beam::beam(self.map, &self.sensor, k, z, &x, &x, p, &self.beams);
            did(self.correct(track, judged, z));
        }
    }
}

/// A scan's stored range as the replay reads it: `None` for no return or
/// no valid reading.
fn range(stored: f32) -> Option<f64> {
    match Stored::of(stored) {
        Stored::Range(r) => Some(f64::from(r)),
        Stored::NoReturn | Stored::Missing => None,
    }
}

/// The replay's start at `pose`: the calibration at its initial values,
/// the covariance `cfg`'s initial one.
fn start(cfg: &Config, pose: [f64; 3]) -> Track<f64, STATE> {
    let mut x = SVector::<f64, STATE>::zeros();
    let mut sd = SVector::<f64, STATE>::zeros();
    for i in 0..3 {
        x[i] = pose[i];
        sd[i] = cfg.initial_std[i];
    }
    for i in 0..4 {
        x[V_SCALE + i] = cfg.calibration.initial[i];
        sd[V_SCALE + i] = cfg.calibration.std[i];
    }
    sd[RANGE_BIAS] = cfg.beams.bias.sigma;
    let p = SMatrix::from_diagonal(&sd.component_mul(&sd));
    Track::new(Belief::new(x, p), 0.0, ())
}

fn bench(c: &mut Criterion) {
    let read = locus_logs::carmen::read(&log_path()).expect("the Intel lab's CARMEN log");
    let poses: Vec<[f64; 3]> = read
        .scan_poses
        .iter()
        .map(|p| [p.x, p.y, p.theta])
        .collect();
    let sensor = read.log.beam_sensors[0];
    let dir = std::env::temp_dir().join(format!("locus-bench-intel-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let map = intel_map(&sensor, &read.log.scans, &poses, &dir);
    std::fs::remove_dir_all(&dir).expect("removing the temporary directory");
    let mut log = Log::from_locus("intel-corrected.log.gz", read.log).expect("the log");
    log.map = Some(SharedMap::from(map));
    let odometry_only = Log {
        scans: Scans::default(),
        ..log.clone()
    };

    let scans = log.scans.len();
    let mut gaps: Vec<f64> = log.scans.times().windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_by(f64::total_cmp);
    println!(
        "Intel lab: {scans} scans of {} beams, {} odometry records, {:.1} s; median time between scans {:.3} s",
        sensor.count,
        log.odometry.len(),
        log.duration(),
        gaps[gaps.len() / 2]
    );
    let (full, default) = (config(180), config(Beams::default().per_scan));
    for (name, cfg) in [("180 beams", &full), ("30 beams", &default)] {
        let r = replay(&log, cfg, |_| ()).expect("replay");
        let b = r.beams;
        println!(
            "Replay, {name} a scan: position RMSE {:.2} m; per scan: {:.1} chosen, no return {:.1}, no surface {:.1}, short {:.1}, applied {:.1} (down-weighted {:.1}), gated {:.1}, unusable {:.1}",
            r.summary.position_rmse,
            f64::from(b.chosen) / scans as f64,
            f64::from(b.no_return) / scans as f64,
            f64::from(b.no_surface) / scans as f64,
            f64::from(b.short) / scans as f64,
            f64::from(b.applied) / scans as f64,
            f64::from(b.down_weighted) / scans as f64,
            f64::from(b.gated) / scans as f64,
            f64::from(b.unusable) / scans as f64,
        );
    }

    let mut group = c.benchmark_group("intel_replay");
    group.sample_size(10);
    group.bench_function("odometry only (scans removed)", |b| {
        b.iter(|| black_box(run(&odometry_only, &full)));
    });
    group.bench_function("30 beams per scan", |b| {
        b.iter(|| black_box(run(&log, &default)));
    });
    group.bench_function("180 beams per scan", |b| {
        b.iter(|| black_box(run(&log, &full)));
    });
    group.finish();

    // One scan at a time at its corrected pose, from the replay's initial
    // covariance.
    let replica = Replica {
        map: log.map.as_deref().expect("the map"),
        sensor,
        beams: full.beams,
        rules: Rules::new(
            Ekf::default()
                .with_gate(ChiSquareGate::new(full.gate.expect("a gate")).expect("the gate")),
        ),
        robust: StudentT::new(full.robust_dof.expect("Student-t")).expect("its dof"),
    };
    let tracks: Vec<Track<f64, STATE>> = poses.iter().map(|&p| start(&full, p)).collect();
    // The planes each scan's beams meet from its corrected pose.
    let planes: Vec<Vec<(PlanarBeam<f64>, f64)>> = log
        .scans
        .iter()
        .zip(&tracks)
        .map(|(scan, t)| {
            scan.ranges
                .iter()
                .enumerate()
                .filter_map(|(k, &r)| Some((replica.plane(k, &t.belief.x)?, range(r)?)))
                .collect()
        })
        .collect();
    // What the beams do, per scan: against the planes cast at the
    // corrected pose (as `updates` times them), and cast from the estimate
    // each update left (as `casts and updates` does).
    let mut fixed = [0usize; 4];
    let mut moving = [0usize; 4];
    for ((t, p), scan) in tracks.iter().zip(&planes).zip(log.scans.iter()) {
        let mut t0 = *t;
        for (m, z) in p {
            fixed[replica.update(&mut t0, m, *z) as usize] += 1;
        }
        let mut t1 = *t;
        replica.scan(&mut t1, scan.ranges, |d| moving[d as usize] += 1);
    }
    let returns = log
        .scans
        .iter()
        .flat_map(|s| s.ranges)
        .filter(|&&r| range(r).is_some())
        .count();
    let met: usize = planes.iter().map(Vec::len).sum();
    println!(
        "At the corrected poses, per scan: {:.1} beams with a return, {:.1} meeting a surface",
        returns as f64 / scans as f64,
        met as f64 / scans as f64
    );
    for (name, tally) in [
        ("updates (planes cast at the corrected pose)", fixed),
        (
            "casts and updates (cast from each update's estimate)",
            moving,
        ),
    ] {
        let [skipped, applied, down, gated] = tally.map(|n| n as f64 / scans as f64);
        println!(
            "  {name}: skipped {skipped:.1}, applied {:.1} (down-weighted {down:.1}), gated {gated:.1}",
            applied + down
        );
    }

    let mut group = c.benchmark_group("intel_scan_180");
    let mut k = 0;
    group.bench_function("casts", |b| {
        b.iter(|| {
            let scan = log.scans.get(k % scans).expect("a scan");
            let x = &tracks[k % scans].belief.x;
            k += 1;
            let mut sum = 0.0;
            for (j, &r) in scan.ranges.iter().enumerate() {
                if range(r).is_some() {
                    sum += replica.plane(j, black_box(x)).map_or(0.0, |m| m.point[0]);
                }
            }
            black_box(sum)
        });
    });
    let mut k = 0;
    group.bench_function("updates", |b| {
        b.iter(|| {
            let mut track = tracks[k % scans];
            let p = &planes[k % scans];
            k += 1;
            for (m, z) in p {
                black_box(replica.update(&mut track, m, *z));
            }
            black_box(track.belief.x[0])
        });
    });
    let mut k = 0;
    group.bench_function("casts and updates", |b| {
        b.iter(|| {
            let scan = log.scans.get(k % scans).expect("a scan");
            let mut track = tracks[k % scans];
            k += 1;
            replica.scan(&mut track, scan.ranges, |d| {
                black_box(d);
            });
            black_box(track.belief.x[0])
        });
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
