//! The grid cast (a bit a cell, the traversal over the index, the normal
//! fitted a row of bits at a time) gives the same hits, bit for bit, as the
//! reference cast it replaced (`Grid::cast_reference`): on rasterised walls,
//! on a noisy grid of scattered cells, with a yawed grid, from inside and
//! outside the grid, along the axes and at every angle, near the edges.

mod common;

use core::f64::consts::PI;

use common::{Rng, random_walls};
use locus_map::{Grid, GridGeometry, Thresholds};

fn agree(grid: &Grid, rng: &mut Rng, rays: usize, lo: f64, hi: f64) -> usize {
    let mut hits = 0;
    for i in 0..rays {
        let origin = [rng.range(lo, hi), rng.range(lo, hi)];
        // Every tenth ray along an axis or a diagonal.
        let angle = if i % 10 == 0 {
            f64::from((i / 10 % 8) as u32) * PI / 4.0
        } else {
            rng.range(-PI, PI)
        };
        hits += agree_all(grid, origin, angle, &[0.0, 0.3, 8.0, f64::INFINITY]);
    }
    hits
}

#[test]
fn the_cast_is_the_reference_cast() {
    let mut rng = Rng::new(29);
    let walls = random_walls(&mut rng, 60, 10.0);
    for yaw in [0.0, 0.3] {
        let geometry = GridGeometry::new(207, 203, 0.05, [-0.2, -0.1, yaw]).unwrap();
        let grid = Grid::rasterise(&walls, geometry, Thresholds::default()).unwrap();
        let hits = agree(&grid, &mut rng, 3000, -1.0, 11.0);
        assert!(hits > 3000, "{hits} hits");
    }
    // Scattered cells (blobs, lone cells, cells on the grid's edges).
    let geometry = GridGeometry::new(67, 71, 0.1, [0.0, 0.0, 0.0]).unwrap();
    let probabilities: Vec<Option<f64>> = (0..geometry.len())
        .map(|_| match rng.unit() {
            u if u < 0.08 => Some(1.0),
            u if u < 0.5 => Some(0.0),
            _ => None,
        })
        .collect();
    let grid = Grid::from_probabilities(geometry, Thresholds::default(), &probabilities).unwrap();
    let hits = agree(&grid, &mut rng, 3000, -0.5, 7.5);
    assert!(hits > 3000, "{hits} hits");
}

/// The cast and the reference cast agree on the ray from `origin` at
/// `angle` for each limit; returns the number of hits.
fn agree_all(grid: &Grid, origin: [f64; 2], angle: f64, limits: &[f64]) -> usize {
    let mut hits = 0;
    for &limit in limits {
        let fast = grid.cast(origin, angle, limit);
        let slow = grid.cast_reference(origin, angle, limit);
        assert_eq!(
            fast, slow,
            "origin {origin:?}, angle {angle}, limit {limit}"
        );
        hits += usize::from(fast.is_some());
    }
    hits
}

/// An angle: uniform, or along an axis or a diagonal, or just off one (a
/// few ulps, and a few 1e-9 rad), or a slope of small integers (rays that
/// pass exactly through cell corners).
fn any_angle(rng: &mut Rng) -> f64 {
    let axis = f64::from((rng.next_u64() % 8) as u32) * PI / 4.0 - PI;
    match rng.next_u64() % 8 {
        0 => axis,
        1 => f64::from_bits(axis.to_bits() + rng.next_u64() % 5) - 2e-9 * rng.unit(),
        2 => {
            let a = f64::from((rng.next_u64() % 7) as u32) - 3.0;
            let b = f64::from((rng.next_u64() % 7) as u32) - 3.0;
            b.atan2(a)
        }
        _ => rng.range(-PI, PI),
    }
}

/// 100 000 random rays on random grids: the Intel lab's size (820 x 820
/// cells at 0.05 m, rasterised walls, yawed and not), sparse and dense
/// scattered cells, grids a cell wide or high; from inside and outside the
/// grid, on cell boundaries and corners, along axes and diagonals, with
/// limits 0, small, long and infinite.
#[test]
fn random_rays_on_random_grids() {
    let mut rng = Rng::new(1987);
    let limits = [0.0, 0.04, 0.3, 2.5, 80.0, f64::INFINITY];
    let mut rays = 0;
    let mut hits = 0;

    // Intel-sized: rays from inside and from outside, origins anywhere or
    // on a cell corner.
    let walls = random_walls(&mut rng, 400, 40.0);
    for yaw in [0.0, 0.3, -2.0] {
        let geometry = GridGeometry::new(820, 820, 0.05, [-0.5, -0.5, yaw]).unwrap();
        let grid = Grid::rasterise(&walls, geometry, Thresholds::default()).unwrap();
        for i in 0..6000 {
            let origin = if i % 4 == 0 {
                let c = [
                    f64::from((rng.next_u64() % 821) as u32),
                    f64::from((rng.next_u64() % 821) as u32),
                ];
                geometry.to_world(c)
            } else {
                [rng.range(-10.0, 50.0), rng.range(-10.0, 50.0)]
            };
            hits += agree_all(&grid, origin, any_angle(&mut rng), &limits);
            rays += limits.len();
        }
    }

    // Scattered cells at several densities, a power-of-two cell size so
    // that boundaries and corners are exact; some grids one cell wide.
    for (w, h, density) in [
        (64, 48, 0.0005),
        (64, 48, 0.005),
        (100, 90, 0.03),
        (37, 41, 0.3),
        (1, 50, 0.02),
        (50, 1, 0.02),
        (3, 3, 0.2),
    ] {
        let geometry = GridGeometry::new(w, h, 0.25, [0.0, 0.0, 0.0]).unwrap();
        let probabilities: Vec<Option<f64>> = (0..geometry.len())
            .map(|_| (rng.unit() < density).then_some(1.0))
            .collect();
        let grid =
            Grid::from_probabilities(geometry, Thresholds::default(), &probabilities).unwrap();
        let (wm, hm) = (w as f64 * 0.25, h as f64 * 0.25);
        for i in 0..2000 {
            let origin = match i % 3 {
                // On a cell corner or edge, inside or just outside.
                0 => [
                    f64::from((rng.next_u64() % (w as u64 + 3)) as u32) * 0.25 - 0.25,
                    f64::from((rng.next_u64() % (h as u64 + 3)) as u32) * 0.25 - 0.25
                        + f64::from(u8::from(i % 2 == 0)) * rng.unit() * 0.25,
                ],
                1 => [rng.range(0.0, wm), rng.range(0.0, hm)],
                _ => [rng.range(-wm, 2.0 * wm), rng.range(-hm, 2.0 * hm)],
            };
            hits += agree_all(&grid, origin, any_angle(&mut rng), &limits);
            rays += limits.len();
        }
    }
    assert!(rays >= 100_000, "{rays} rays");
    assert!(hits > rays / 8, "{hits} hits of {rays}");
}

/// Cells set occupied or free after the grid is built: the hits follow.
#[test]
fn cells_set_later() {
    let mut rng = Rng::new(3);
    let geometry = GridGeometry::new(120, 100, 0.05, [0.0, 0.0, 0.1]).unwrap();
    let mut grid =
        Grid::from_probabilities(geometry, Thresholds::default(), &vec![Some(0.0); 12_000])
            .unwrap();
    let limits = [0.1, 3.0, f64::INFINITY];
    let mut hits = 0;
    for round in 0..60 {
        for _ in 0..10 {
            let (x, y) = (
                (rng.next_u64() % 120) as usize,
                (rng.next_u64() % 100) as usize,
            );
            let p = if round % 3 == 2 { 0.0 } else { 1.0 };
            grid.set(x, y, Some(p)).unwrap();
        }
        for _ in 0..100 {
            let origin = [rng.range(-1.0, 7.0), rng.range(-1.0, 6.0)];
            hits += agree_all(&grid, origin, any_angle(&mut rng), &limits);
        }
    }
    assert!(hits > 3000, "{hits} hits");
}
