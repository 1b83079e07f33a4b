//! Casting allocates nothing, on segment maps (indexed or not) and grids,
//! and neither does adding a beam to a `GridBuilder`: measured under
//! allocation-counter's counting allocator.

mod common;

use core::f64::consts::PI;

use common::{Rng, random_walls};
use locus_map::{
    BuilderConfig, Grid, GridBuilder, GridGeometry, Map, Reading, SegmentMap, Thresholds,
};

#[test]
fn casts_do_not_allocate() {
    let mut rng = Rng::new(5);
    let walls = random_walls(&mut rng, 100, 20.0);
    let geometry = GridGeometry::covering([0.0, 0.0], [20.0, 20.0], 0.5, 0.05).unwrap();
    let maps = [
        Map::from(SegmentMap::new(walls.clone()).unwrap()),
        Map::from(SegmentMap::new(walls[..8].to_vec()).unwrap()),
        Map::from(Grid::rasterise(&walls, geometry, Thresholds::default()).unwrap()),
    ];
    let rays: Vec<_> = (0..2000)
        .map(|_| {
            (
                [rng.range(-5.0, 25.0), rng.range(-5.0, 25.0)],
                rng.range(-PI, PI),
            )
        })
        .collect();
    let mut builder = GridBuilder::new(geometry, BuilderConfig::default()).unwrap();

    let control = allocation_counter::measure(|| {
        core::hint::black_box(Vec::<u8>::with_capacity(1));
    });
    assert_eq!(
        control.count_total, 1,
        "the counting allocator is not active"
    );
    let mut hits = 0usize;
    let info = allocation_counter::measure(|| {
        for map in &maps {
            for &(o, a) in &rays {
                hits += usize::from(map.cast(o, a, 30.0).is_some());
            }
        }
        for &(o, a) in &rays {
            builder.insert_beam(o, a, Reading::Range(3.0));
            builder.insert_beam(o, a, Reading::NoReturn);
        }
    });
    assert_eq!(info.count_total, 0);
    assert!(hits > 3000);
}
