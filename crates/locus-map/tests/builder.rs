//! Occupancy mapping with known poses: scans cast on a wall map, mapped, give
//! a grid whose occupied cells lie on the walls and whose casts agree with
//! the walls'; beams with no return clear but mark nothing.

mod common;

use core::f64::consts::PI;

use common::{Rng, random_walls};
use locus_map::{
    Beam, BuilderConfig, GridBuilder, GridGeometry, HitSource, Occupancy, Reading, SegmentMap,
};

#[test]
fn mapping_a_known_world_recovers_its_walls() {
    let mut rng = Rng::new(9);
    let walls = random_walls(&mut rng, 20, 10.0);
    let world = SegmentMap::new(walls.clone()).unwrap();
    let geometry = GridGeometry::covering([0.0, 0.0], [10.0, 10.0], 1.0, 0.05).unwrap();
    let mut builder = GridBuilder::new(geometry, BuilderConfig::default()).unwrap();
    let max_range = 8.0;
    let angles: Vec<f64> = (0..180)
        .map(|k| -PI / 2.0 + PI * k as f64 / 179.0)
        .collect();
    let mut poses = Vec::new();
    while poses.len() < 300 {
        let pose = [rng.range(0.3, 9.7), rng.range(0.3, 9.7), rng.range(-PI, PI)];
        let beams: Vec<Beam> = angles
            .iter()
            .map(|&a| Beam {
                angle: a,
                range: world
                    .cast([pose[0], pose[1]], pose[2] + a, max_range)
                    .map_or(f64::INFINITY, |h| h.range),
            })
            .collect();
        builder.insert_scan(pose, &beams, max_range);
        poses.push(pose);
    }
    let grid = builder.finish();
    let (occupied, free, unknown) = grid.counts();
    assert!(
        occupied > 1000 && free > 20_000 && unknown > 0,
        "{occupied} {free} {unknown}"
    );
    // Outside the walls nothing was seen.
    assert_eq!(grid.state(2, 2), Some(Occupancy::Unknown));
    assert_eq!(grid.probability(2, 2), None);
    // Casts on the map agree with casts on the world.
    let res = geometry.resolution();
    let (mut close, mut n) = (0, 0);
    for k in 0..2000 {
        let p = poses[k % poses.len()];
        let a = rng.range(-PI, PI);
        let Some(want) = world.cast([p[0], p[1]], a, max_range) else {
            continue;
        };
        n += 1;
        let Some(got) = grid.cast([p[0], p[1]], a, max_range) else {
            continue;
        };
        assert!(matches!(got.source, HitSource::Cell(_)));
        if (got.range - want.range).abs() <= 2.0 * res / want.incidence.cos().max(0.2) {
            close += 1;
        }
    }
    println!("{close} of {n} casts on the map within two cells of the world's");
    assert!(
        n > 1000 && close as f64 >= 0.95 * n as f64,
        "{close} of {n}"
    );
}

#[test]
fn beams_clear_and_mark() {
    let g = GridGeometry::new(20, 5, 1.0, [0.0, 0.0, 0.0]).unwrap();
    let config = BuilderConfig {
        clear_limit: 6.0,
        ..BuilderConfig::default()
    };
    // No return: cells up to clear_limit become less likely occupied, none
    // more; beyond, untouched.
    let mut b = GridBuilder::new(g, config).unwrap();
    b.insert_beam([0.5, 2.5], 0.0, Reading::NoReturn);
    let grid = b.finish();
    for ix in 0..=6 {
        assert!(grid.probability(ix, 2).unwrap() < 0.5, "{ix}");
    }
    assert_eq!(grid.probability(7, 2), None);
    assert_eq!(grid.counts().0, 0);

    // A return: misses up to the cell of its end, a hit there; repeated, the
    // probabilities reach the clamps.
    let mut b = GridBuilder::new(g, config).unwrap();
    for _ in 0..50 {
        b.insert_scan(
            [0.5, 2.5, 0.0],
            &[Beam {
                angle: 0.0,
                range: 9.0,
            }],
            10.0,
        );
    }
    let grid = b.finish();
    assert!((grid.probability(9, 2).unwrap() - 0.97).abs() < 1e-6);
    assert_eq!(grid.state(9, 2), Some(Occupancy::Occupied));
    assert!((grid.probability(8, 2).unwrap() - 0.12).abs() < 1e-6);
    assert_eq!(grid.state(8, 2), Some(Occupancy::Free));
    assert_eq!(grid.probability(10, 2), None);

    // A return beyond the grid, at or beyond max_range, or bad input: clears
    // only, or nothing.
    let mut b = GridBuilder::new(g, config).unwrap();
    b.insert_beam([0.5, 2.5], 0.0, Reading::Range(40.0));
    b.insert_scan(
        [0.5, 1.5, 0.0],
        &[Beam {
            angle: 0.0,
            range: 3.0,
        }],
        3.0,
    );
    b.insert_beam([0.5, 3.5], 0.0, Reading::Range(f64::NAN));
    b.insert_beam([0.5, 3.5], 0.0, Reading::Range(-1.0));
    b.insert_beam([f64::NAN, 3.5], 0.0, Reading::Range(1.0));
    let grid = b.finish();
    assert_eq!(grid.counts().0, 0);
    assert!(grid.probability(19, 2).unwrap() < 0.5);
    assert_eq!(grid.probability(0, 3), None);
}

#[test]
fn bad_configurations_are_refused() {
    let g = GridGeometry::new(2, 2, 1.0, [0.0, 0.0, 0.0]).unwrap();
    let d = BuilderConfig::default();
    for bad in [
        BuilderConfig { p_hit: 0.5, ..d },
        BuilderConfig { p_miss: 0.6, ..d },
        BuilderConfig { p_min: 0.0, ..d },
        BuilderConfig { p_max: 1.0, ..d },
        BuilderConfig {
            clear_limit: f64::NAN,
            ..d
        },
        BuilderConfig {
            thresholds: locus_map::Thresholds {
                occupied: 0.1,
                free: 0.2,
            },
            ..d
        },
    ] {
        assert!(GridBuilder::new(g, bad).is_err(), "{bad:?}");
    }
    assert!(GridGeometry::new(0, 2, 1.0, [0.0; 3]).is_err());
    assert!(GridGeometry::new(2, 2, 0.0, [0.0; 3]).is_err());
    assert!(GridGeometry::new(2, 2, 1.0, [0.0, f64::NAN, 0.0]).is_err());
}
