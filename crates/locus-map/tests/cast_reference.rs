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
        for limit in [0.0, 0.3, 8.0, f64::INFINITY] {
            let fast = grid.cast(origin, angle, limit);
            let slow = grid.cast_reference(origin, angle, limit);
            assert_eq!(
                fast, slow,
                "origin {origin:?}, angle {angle}, limit {limit}"
            );
            hits += usize::from(fast.is_some());
        }
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
