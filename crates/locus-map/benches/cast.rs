//! A 180-beam scan cast on a wall map of 100 random walls (20 m square) and
//! on the same walls rasterised into a 420 x 420 grid at 0.05 m; beams span
//! 360 degrees from 16 poses inside the map, with an 8 m range limit (the
//! simulator's and Intel lab's lidar's) and without one. An Intel-lab-sized
//! grid too: 400 random walls on a 40 m square at 0.05 m (820 x 820 cells),
//! with the Intel replay's 80 m range limit. Beside each grid's
//! cast, the reference cast it replaced (`Grid::cast_reference`, the same
//! hits), as its peer in the same run. Criterion reports
//! the time per scan; divide by 180 for the time per beam (the throughput it
//! prints is beams per second).
//!
//! Run: `cargo bench -p locus-map --bench cast`.

use core::f64::consts::PI;
use core::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use locus_map::{Grid, GridGeometry, Hit, Map, Segment, SegmentMap, Thresholds};

const BEAMS: usize = 180;

/// SplitMix64.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// `n - 4` random walls 0.5 to 4 m long plus the four sides of an `s` m
/// square.
fn random_walls(rng: &mut Rng, n: usize, s: f64) -> Vec<Segment> {
    let mut out = vec![
        Segment::new([0.0, 0.0], [s, 0.0]),
        Segment::new([s, 0.0], [s, s]),
        Segment::new([s, s], [0.0, s]),
        Segment::new([0.0, s], [0.0, 0.0]),
    ];
    while out.len() < n {
        let a = [rng.range(0.5, s - 0.5), rng.range(0.5, s - 0.5)];
        let (l, th) = (rng.range(0.5, 4.0), rng.range(-PI, PI));
        let b = [a[0] + l * th.cos(), a[1] + l * th.sin()];
        if b.iter().all(|&x| x > 0.2 && x < s - 0.2) {
            out.push(Segment::new(a, b));
        }
    }
    out
}

/// Benchmarks `cast` over a 180-beam scan from each of `poses` in turn.
fn scan(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    poses: &[[f64; 3]],
    cast: impl Fn([f64; 2], f64) -> Option<Hit>,
) {
    let mut k = 0;
    group.bench_function(name, |b| {
        b.iter(|| {
            let p = poses[k % poses.len()];
            k += 1;
            let mut sum = 0.0;
            for i in 0..BEAMS {
                let a = p[2] + 2.0 * PI * i as f64 / BEAMS as f64;
                if let Some(h) = cast(black_box([p[0], p[1]]), black_box(a)) {
                    sum += h.range + h.incidence;
                }
            }
            black_box(sum)
        });
    });
}

fn bench(c: &mut Criterion) {
    let mut rng = Rng(29);
    let walls = random_walls(&mut rng, 100, 20.0);
    let geometry = GridGeometry::covering([0.0, 0.0], [20.0, 20.0], 0.5, 0.05).unwrap();
    let segments = Map::from(SegmentMap::new(walls.clone()).unwrap());
    let grid = Grid::rasterise(&walls, geometry, Thresholds::default()).unwrap();
    let grid_map = Map::from(grid.clone());
    let poses: Vec<[f64; 3]> = (0..16)
        .map(|_| {
            [
                rng.range(1.0, 19.0),
                rng.range(1.0, 19.0),
                rng.range(-PI, PI),
            ]
        })
        .collect();
    let mut group = c.benchmark_group("scan_180");
    group.throughput(Throughput::Elements(BEAMS as u64));
    for (limit_name, limit) in [("8m", 8.0), ("unlimited", f64::INFINITY)] {
        scan(
            &mut group,
            &format!("segments_100/{limit_name}"),
            &poses,
            |o, a| segments.cast(o, a, limit),
        );
        scan(
            &mut group,
            &format!("grid_420x420/{limit_name}"),
            &poses,
            |o, a| grid_map.cast(o, a, limit),
        );
        scan(
            &mut group,
            &format!("grid_420x420_reference/{limit_name}"),
            &poses,
            |o, a| grid.cast_reference(o, a, limit),
        );
    }
    let big_walls = random_walls(&mut rng, 400, 40.0);
    let big_geometry = GridGeometry::covering([0.0, 0.0], [40.0, 40.0], 0.5, 0.05).unwrap();
    let big = Grid::rasterise(&big_walls, big_geometry, Thresholds::default()).unwrap();
    let big_map = Map::from(big.clone());
    let big_poses: Vec<[f64; 3]> = (0..16)
        .map(|_| {
            [
                rng.range(1.0, 39.0),
                rng.range(1.0, 39.0),
                rng.range(-PI, PI),
            ]
        })
        .collect();
    scan(&mut group, "grid_820x820/80m", &big_poses, |o, a| {
        big_map.cast(o, a, 80.0)
    });
    scan(
        &mut group,
        "grid_820x820_reference/80m",
        &big_poses,
        |o, a| big.cast_reference(o, a, 80.0),
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
