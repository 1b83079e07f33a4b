//! The planar range model's analytic derivatives against central finite
//! differences of `cast` on segment maps (GTSAM's habit: every analytic
//! Jacobian checked numerically).

mod common;

use core::f64::consts::PI;

use common::{Rng, random_walls};
use locus_map::{Segment, SegmentMap, planar_range};

/// Central difference step (m and rad).
const H: f64 = 1e-6;

#[test]
fn planar_jacobian_matches_finite_differences_of_cast() {
    let mut rng = Rng::new(1);
    let walls = random_walls(&mut rng, 100, 20.0);
    let map = SegmentMap::new(walls.clone()).unwrap();
    let mut checked = 0;
    while checked < 2000 {
        let o = [rng.range(0.0, 20.0), rng.range(0.0, 20.0)];
        let a = rng.range(-PI, PI);
        let Some(hit) = map.cast(o, a, f64::INFINITY) else {
            continue;
        };
        // Away from grazing and from the wall's ends, so that the nudged rays
        // hit the same wall.
        if hit.incidence > 75f64.to_radians() {
            continue;
        }
        let locus_map::HitSource::Segment(i) = hit.source else {
            unreachable!()
        };
        let w = walls[i];
        let near_end = [w.a, w.b]
            .iter()
            .any(|e| (e[0] - hit.point[0]).hypot(e[1] - hit.point[1]) < 1e-3);
        let same = |h: Option<locus_map::Hit>| h.map(|h| h.source) == Some(hit.source);
        let nudged = [
            map.cast([o[0] + H, o[1]], a, f64::INFINITY),
            map.cast([o[0] - H, o[1]], a, f64::INFINITY),
            map.cast([o[0], o[1] + H], a, f64::INFINITY),
            map.cast([o[0], o[1] - H], a, f64::INFINITY),
            map.cast(o, a + H, f64::INFINITY),
            map.cast(o, a - H, f64::INFINITY),
        ];
        if near_end || !nudged.iter().all(|h| same(*h)) {
            continue;
        }
        let r = nudged.map(|h| h.unwrap().range);
        let fd = [
            (r[0] - r[1]) / (2.0 * H),
            (r[2] - r[3]) / (2.0 * H),
            (r[4] - r[5]) / (2.0 * H),
        ];
        let j = hit.planar(o, a).expect("not grazing");
        assert!((j.range - hit.range).abs() < 1e-9 * (1.0 + hit.range));
        let analytic = [j.d_origin[0], j.d_origin[1], j.d_angle];
        for k in 0..3 {
            let tol = 1e-5 * (1.0 + analytic[k].abs());
            assert!(
                (fd[k] - analytic[k]).abs() < tol,
                "{o:?} {a}: component {k}: analytic {} numeric {}",
                analytic[k],
                fd[k]
            );
        }
        checked += 1;
    }
}

#[test]
fn planar_model_known_values_and_grazing() {
    // Wall x = 2, normal n = (-1, 0), n.d = -cos a: r = 2 / cos a,
    // dr/do = -n / (n.d) = (-1 / cos a, 0), dr/da = 2 sin a / cos^2 a.
    let a: f64 = 0.4;
    let j = planar_range([2.0, 7.0], [-1.0, 0.0], [0.0, 0.0], a).unwrap();
    assert!((j.range - 2.0 / a.cos()).abs() < 1e-12);
    assert!((j.d_origin[0] + 1.0 / a.cos()).abs() < 1e-12);
    assert_eq!(j.d_origin[1], 0.0);
    assert!((j.d_angle - 2.0 * a.sin() / (a.cos() * a.cos())).abs() < 1e-12);
    // Parallel to the wall: no finite range.
    assert!(
        planar_range(
            [2.0, 0.0],
            [-1.0, 0.0],
            [0.0, 0.0],
            core::f64::consts::FRAC_PI_2
        )
        .is_none()
    );
    assert!(planar_range([2.0, 0.0], [-1.0, 0.0], [f64::NAN, 0.0], 0.0).is_none());
    // A hit's plane reproduces its range.
    let map = SegmentMap::new(vec![Segment::new([3.0, -1.0], [1.0, 4.0])]).unwrap();
    let h = map.cast([0.0, 0.0], 0.7, 10.0).unwrap();
    assert!((h.planar([0.0, 0.0], 0.7).unwrap().range - h.range).abs() < 1e-12);
}
