//! Segment casts against a brute-force reference, their normals and
//! incidence, and the degenerate cases the documentation names.

mod common;

use core::f64::consts::{FRAC_PI_2, FRAC_PI_3, PI};

use common::{Rng, angle_between, brute_cast, random_walls};
use locus_map::{HitSource, Map, Segment, SegmentMap};

/// Random rays on random maps, indexed (many walls) and not (few): the same
/// nearest wall and range as the brute-force reference, from inside and
/// outside the map, with finite and infinite range limits.
#[test]
fn casts_match_brute_force() {
    let mut rng = Rng::new(29);
    let mut hits = 0;
    for (n, maps) in [(100, 4), (300, 2), (8, 4)] {
        for _ in 0..maps {
            let walls = random_walls(&mut rng, n, 20.0);
            let map = SegmentMap::new(walls.clone()).unwrap();
            for k in 0..5000 {
                let o = if k % 5 == 0 {
                    [rng.range(-10.0, 30.0), rng.range(-10.0, 30.0)]
                } else {
                    [rng.range(0.0, 20.0), rng.range(0.0, 20.0)]
                };
                let angle = rng.range(-PI, PI);
                let max_range = if k % 3 == 0 {
                    f64::INFINITY
                } else {
                    rng.range(0.0, 15.0)
                };
                let got = map.cast(o, angle, max_range);
                let want = brute_cast(&walls, o, angle, max_range);
                match (got, want) {
                    (None, None) => {}
                    (Some(h), Some((t, i))) => {
                        hits += 1;
                        assert!(
                            (h.range - t).abs() <= 1e-9 * (1.0 + t),
                            "{o:?} {angle}: {} vs {t}",
                            h.range
                        );
                        let HitSource::Segment(j) = h.source else {
                            panic!("not a segment")
                        };
                        // Another wall at the same range (a shared corner) is as good.
                        if j != i {
                            let alt = walls[j]
                                .intersect(o, [angle.cos(), angle.sin()], max_range)
                                .unwrap();
                            assert!((alt - t).abs() <= 1e-9 * (1.0 + t));
                        }
                        let d = [angle.cos(), angle.sin()];
                        assert!(
                            (h.point[0] - (o[0] + h.range * d[0])).abs() < 1e-12 * (1.0 + h.range)
                        );
                        assert!(
                            (h.point[1] - (o[1] + h.range * d[1])).abs() < 1e-12 * (1.0 + h.range)
                        );
                    }
                    (g, w) => panic!("{o:?} {angle} {max_range}: cast {g:?}, reference {w:?}"),
                }
            }
        }
    }
    assert!(hits > 30_000, "too few hits to mean anything: {hits}");
}

/// Normals are unit, face the ray, are perpendicular to the wall hit, and the
/// incidence is the angle between them and the reversed ray.
#[test]
fn normals_and_incidence() {
    let mut rng = Rng::new(7);
    let walls = random_walls(&mut rng, 100, 20.0);
    let map = SegmentMap::new(walls.clone()).unwrap();
    for _ in 0..5000 {
        let o = [rng.range(0.0, 20.0), rng.range(0.0, 20.0)];
        let angle = rng.range(-PI, PI);
        let d = [angle.cos(), angle.sin()];
        let Some(h) = map.cast(o, angle, f64::INFINITY) else {
            continue;
        };
        let HitSource::Segment(i) = h.source else {
            unreachable!()
        };
        let n = h.normal;
        assert!((n[0].hypot(n[1]) - 1.0).abs() < 1e-12);
        assert!(n[0] * d[0] + n[1] * d[1] <= 0.0);
        let e = [walls[i].b[0] - walls[i].a[0], walls[i].b[1] - walls[i].a[1]];
        assert!((n[0] * e[0] + n[1] * e[1]).abs() < 1e-9 * walls[i].length());
        assert!((h.incidence - angle_between(n, [-d[0], -d[1]])).abs() < 1e-9);
        assert!((0.0..=FRAC_PI_2).contains(&h.incidence));
    }
}

#[test]
fn incidence_of_known_rays() {
    let map = SegmentMap::new(vec![Segment::new([2.0, -50.0], [2.0, 50.0])]).unwrap();
    // Head-on from the left: normal (-1, 0), incidence 0.
    let h = map.cast([0.0, 0.0], 0.0, 10.0).unwrap();
    assert_eq!(h.range, 2.0);
    assert_eq!(h.normal, [-1.0, 0.0]);
    assert_eq!(h.incidence, 0.0);
    // From the right, the normal flips to face the ray.
    let h = map.cast([4.0, 0.0], PI, 10.0).unwrap();
    assert_eq!(h.normal, [1.0, 0.0]);
    // 60 degrees off the normal: range 2 / cos 60 = 4.
    let h = map.cast([0.0, 0.0], FRAC_PI_3, 10.0).unwrap();
    assert!((h.range - 4.0).abs() < 1e-12);
    assert!((h.incidence - FRAC_PI_3).abs() < 1e-12);
    // Nearly grazing.
    let h = map.cast([0.0, 0.0], FRAC_PI_2 - 0.1, 100.0).unwrap();
    assert!((h.incidence - (FRAC_PI_2 - 0.1)).abs() < 1e-12);
}

#[test]
fn degenerate_cases() {
    let wall = Segment::new([1.0, -1.0], [1.0, 1.0]);
    // Empty map.
    let empty = SegmentMap::new(vec![]).unwrap();
    assert!(empty.cast([0.0, 0.0], 0.0, 10.0).is_none());
    assert!(empty.bounds().is_none());
    // A zero-length segment is kept but never hit, even head-on.
    let dot = SegmentMap::new(vec![Segment::new([1.0, 0.0], [1.0, 0.0])]).unwrap();
    assert_eq!(dot.segments().len(), 1);
    assert!(dot.cast([0.0, 0.0], 0.0, 10.0).is_none());
    let map = SegmentMap::new(vec![wall]).unwrap();
    // max_range 0: no hit unless the origin is on the wall (then range 0).
    assert!(map.cast([0.0, 0.0], 0.0, 0.0).is_none());
    let h = map.cast([1.0, 0.5], 0.0, 0.0).unwrap();
    assert_eq!(h.range, 0.0);
    assert_eq!(h.point, [1.0, 0.5]);
    // Just short of the wall, exactly at it.
    assert!(map.cast([0.0, 0.0], 0.0, 1.0 - 1e-12).is_none());
    assert_eq!(map.cast([0.0, 0.0], 0.0, 1.0).unwrap().range, 1.0);
    // A ray along the wall (collinear) does not hit it; the wall's end does
    // count for a crossing ray.
    assert!(map.cast([1.0, -3.0], FRAC_PI_2, 10.0).is_none());
    assert!(map.cast([0.0, 1.0], 0.0, 10.0).is_some());
    // Pointing away; bad inputs.
    assert!(map.cast([0.0, 0.0], PI, 10.0).is_none());
    assert!(map.cast([f64::NAN, 0.0], 0.0, 10.0).is_none());
    assert!(map.cast([0.0, 0.0], f64::INFINITY, 10.0).is_none());
    assert!(map.cast([0.0, 0.0], 0.0, -1.0).is_none());
    assert!(map.cast([0.0, 0.0], 0.0, f64::NAN).is_none());
    // Non-finite walls are refused, naming the segment.
    let err = SegmentMap::new(vec![wall, Segment::new([0.0, f64::NAN], [1.0, 1.0])]).unwrap_err();
    assert!(err.to_string().contains("segment 1"), "{err}");
}

/// A map of many walls through the `Map` front: a ray from far outside
/// crosses empty index cells to reach the map.
#[test]
fn from_outside_through_the_index() {
    let mut rng = Rng::new(3);
    let walls = random_walls(&mut rng, 60, 20.0);
    let map = Map::from(SegmentMap::new(walls).unwrap());
    let h = map.cast([-100.0, 10.0], 0.0, f64::INFINITY).unwrap();
    assert!((h.range - 100.0).abs() < 1e-9);
    assert_eq!(h.normal, [-1.0, 0.0]);
    assert!(map.cast([-100.0, 10.0], 0.0, 99.0).is_none());
    assert!(map.cast([-100.0, 10.0], PI, f64::INFINITY).is_none());
}
