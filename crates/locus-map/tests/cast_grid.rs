//! Grid casts against segment casts of the same walls rasterised, normals
//! estimated from the occupied neighbourhood, the grid's yaw, and the
//! degenerate cases the documentation names.

mod common;

use core::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use common::{Rng, angle_between, random_walls};
use locus_map::{Grid, GridGeometry, HitSource, Occupancy, Segment, SegmentMap, Thresholds};

/// Distance (m) from `p` to the segment `s`.
fn distance(p: [f64; 2], s: &Segment) -> f64 {
    let e = [s.b[0] - s.a[0], s.b[1] - s.a[1]];
    let l2 = e[0] * e[0] + e[1] * e[1];
    let u = if l2 == 0.0 {
        0.0
    } else {
        (((p[0] - s.a[0]) * e[0] + (p[1] - s.a[1]) * e[1]) / l2).clamp(0.0, 1.0)
    };
    (p[0] - s.a[0] - u * e[0]).hypot(p[1] - s.a[1] - u * e[1])
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Within one cell of the exact cast: the grid range is never beyond the
/// wall's (the crossing lies in an occupied cell), its hit point is within a
/// cell's diagonal of a wall, and, away from grazing, its range is within a
/// cell's diagonal (over the cosine of the incidence) of the wall's.
#[test]
fn grid_casts_agree_with_segment_casts() {
    let res = 0.05;
    let diag = res * 2f64.sqrt();
    let mut rng = Rng::new(11);
    let mut near = 0usize;
    let mut compared = 0usize;
    let mut normal_errors = Vec::new();
    for _ in 0..3 {
        let walls = random_walls(&mut rng, 100, 20.0);
        let segs = SegmentMap::new(walls.clone()).unwrap();
        let geometry = GridGeometry::covering([0.0, 0.0], [20.0, 20.0], 0.5, res).unwrap();
        let grid = Grid::rasterise(&walls, geometry, Thresholds::default()).unwrap();
        for _ in 0..4000 {
            let o = [rng.range(0.1, 19.9), rng.range(0.1, 19.9)];
            let [ix, iy] = geometry.cell_of(o).unwrap();
            if grid.state(ix, iy) == Some(Occupancy::Occupied) {
                continue;
            }
            let angle = rng.range(-PI, PI);
            let max_range = 30.0;
            let g = grid
                .cast(o, angle, max_range)
                .expect("the walls close the map");
            let wall_distance = walls
                .iter()
                .map(|w| distance(g.point, w))
                .fold(f64::INFINITY, f64::min);
            assert!(
                wall_distance <= diag + 1e-9,
                "{o:?} {angle}: {wall_distance}"
            );
            let s = segs.cast(o, angle, max_range).unwrap();
            assert!(
                g.range <= s.range + 1e-9,
                "{o:?} {angle}: grid {} beyond wall {}",
                g.range,
                s.range
            );
            if s.incidence <= 60f64.to_radians() {
                compared += 1;
                if s.range - g.range <= diag / s.incidence.cos() + 1e-9 {
                    near += 1;
                } else {
                    // Otherwise the grid stopped at another wall that the
                    // exact ray passes within a cell of.
                    let HitSource::Segment(si) = s.source else {
                        unreachable!()
                    };
                    let (gi, _) = walls
                        .iter()
                        .enumerate()
                        .map(|(j, w)| (j, distance(g.point, w)))
                        .fold((0, f64::INFINITY), |b, x| if x.1 < b.1 { x } else { b });
                    assert_ne!(
                        gi, si,
                        "{o:?} {angle}: same wall, grid {} exact {}",
                        g.range, s.range
                    );
                }
            }
            // Normals: hits on a wall well away from any end or other wall.
            let HitSource::Segment(i) = s.source else {
                unreachable!()
            };
            let clear = walls.iter().enumerate().all(|(j, w)| {
                let ends = distance(w.a, &Segment::new(s.point, s.point))
                    .min(distance(w.b, &Segment::new(s.point, s.point)));
                if j == i {
                    ends > 0.5
                } else {
                    distance(s.point, w) > 0.5
                }
            });
            if clear && s.range - g.range < diag / s.incidence.cos().max(0.1) + 1e-9 {
                normal_errors.push(angle_between(g.normal, s.normal).to_degrees());
            }
        }
    }
    let share = near as f64 / compared as f64;
    println!("{near} of {compared} casts within a cell along the ray");
    assert!(share >= 0.9, "{near} of {compared} within a cell");
    let n = normal_errors.len();
    let median = percentile(&mut normal_errors, 0.5);
    let p95 = percentile(&mut normal_errors, 0.95);
    let max = percentile(&mut normal_errors, 1.0);
    println!(
        "normal error over {n} hits: median {median:.2} deg, 95 % {p95:.2} deg, max {max:.2} deg"
    );
    assert!(n > 2000);
    assert!(median < 1.0 && p95 < 8.0, "median {median}, 95 % {p95}");
}

/// A straight axis-aligned or 45-degree wall: the fitted normal is exact, so
/// the incidence is the ray's, grazing included (where the entered face
/// would say head-on).
#[test]
fn straight_walls_give_exact_normals() {
    let g = GridGeometry::covering([-5.0, -5.0], [5.0, 5.0], 0.0, 0.1).unwrap();
    let vertical = Grid::rasterise(
        &[Segment::new([2.05, -5.0], [2.05, 5.0])],
        g,
        Thresholds::default(),
    )
    .unwrap();
    for deg in [0.0, 30.0, 60.0, 80.0, 85.0] {
        let a = f64::to_radians(deg);
        let h = vertical.cast([1.5, -4.0], a, 100.0).unwrap();
        assert!(
            angle_between(h.normal, [-1.0, 0.0]) < 1e-12,
            "{deg}: {:?}",
            h.normal
        );
        assert!((h.incidence - a).abs() < 1e-12, "{deg}");
    }
    let diagonal = Grid::rasterise(
        &[Segment::new([-5.0, 5.0], [5.0, -5.0])],
        g,
        Thresholds::default(),
    )
    .unwrap();
    let h = diagonal.cast([-2.0, -2.0], FRAC_PI_4, 100.0).unwrap();
    let s = 0.5f64.sqrt();
    assert!(angle_between(h.normal, [-s, -s]) < 1e-9, "{:?}", h.normal);
    assert!(h.incidence < 1e-9);
    // Grazing along the diagonal: the face entered is axis-aligned (45
    // degrees off), the fitted normal is not.
    let h = diagonal.cast([-3.0, 2.9], -FRAC_PI_4 + 0.2, 100.0).unwrap();
    assert!(
        (h.incidence - (FRAC_PI_2 - 0.2)).abs() < 1e-9,
        "{}",
        h.incidence
    );
}

/// A grid rotated by its origin's yaw casts as the same walls rotated.
#[test]
fn yaw_of_the_origin_is_honoured() {
    let yaw = 0.3;
    let (s, c) = f64::sin_cos(yaw);
    let rot = |p: [f64; 2]| [1.0 + c * p[0] - s * p[1], 2.0 + s * p[0] + c * p[1]];
    // In the grid frame: a wall at x = 3.025 m across the grid.
    let g = GridGeometry::new(100, 100, 0.05, [1.0, 2.0, yaw]).unwrap();
    let wall = Segment::new(rot([3.025, 0.0]), rot([3.025, 5.0]));
    let grid = Grid::rasterise(&[wall], g, Thresholds::default()).unwrap();
    let o = rot([1.0, 2.5]);
    let h = grid.cast(o, yaw, 10.0).unwrap();
    assert!((h.range - 2.0).abs() < 1e-9, "{}", h.range);
    assert!(angle_between(h.normal, [-c, -s]) < 1e-9);
    assert!(h.incidence < 1e-9);
    let HitSource::Cell([ix, _]) = h.source else {
        unreachable!()
    };
    assert_eq!(ix, 60);
}

#[test]
fn degenerate_cases() {
    let g = GridGeometry::new(10, 10, 1.0, [0.0, 0.0, 0.0]).unwrap();
    // All unknown: nothing to hit.
    let unknown = Grid::new(g, Thresholds::default()).unwrap();
    assert!(unknown.cast([5.5, 5.5], 0.0, 100.0).is_none());
    // A lone occupied cell: the normal is the face entered.
    let mut grid = Grid::from_probabilities(g, Thresholds::default(), &[Some(0.0); 100]).unwrap();
    grid.set(7, 5, Some(1.0)).unwrap();
    let h = grid.cast([5.5, 5.5], 0.3, 100.0).unwrap();
    assert!((h.range - 1.5 / 0.3f64.cos()).abs() < 1e-12);
    assert_eq!(h.normal, [-1.0, 0.0]);
    // Starting inside an occupied cell: range 0 at the origin, normal facing
    // the ray; max_range 0 hits only there.
    let h = grid.cast([7.2, 5.5], 0.3, 100.0).unwrap();
    assert_eq!(h.range, 0.0);
    assert_eq!(h.point, [7.2, 5.5]);
    assert_eq!(h.normal, [-0.3f64.cos(), -0.3f64.sin()]);
    assert!(grid.cast([7.2, 5.5], 0.0, 0.0).is_some());
    assert!(grid.cast([5.5, 5.5], 0.0, 0.0).is_none());
    assert!(grid.cast([5.5, 5.5], 0.0, 1.49).is_none());
    assert!(grid.cast([5.5, 5.5], 0.0, 1.5).is_some());
    // From outside the grid, entering it; pointing away; bad inputs.
    let h = grid.cast([-10.0, 5.5], 0.0, 100.0).unwrap();
    assert_eq!(h.range, 17.0);
    assert!(grid.cast([-10.0, 5.5], PI, 100.0).is_none());
    assert!(grid.cast([5.5, 5.5], 0.0, f64::NAN).is_none());
    assert!(grid.cast([5.5, f64::INFINITY], 0.0, 10.0).is_none());
    // Out-of-range cells and probabilities are refused.
    assert!(grid.set(10, 0, Some(0.5)).is_err());
    assert!(grid.set(0, 0, Some(1.5)).is_err());
    assert!(grid.set(0, 0, Some(f64::NAN)).is_err());
    assert_eq!(grid.state(10, 0), None);
    assert_eq!(grid.probability(7, 5), Some(1.0));
}
