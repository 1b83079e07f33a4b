//! Tests of the simulator's sensors: encoders through the quadrature decoder,
//! the Sharp IR curve and pair, the laser, reproducibility.

use locus_models::IrPair;
use locus_models::laser_wall::{LaserMount, Segment};
use locus_odometry::{Wheel, wrapping_diff};
use locus_sim::sensors::{Encoder, IrPairSensor, Laser, SharpIr};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

fn rng(seed: u64) -> StdRng {
    StdRng::seed_from_u64(seed)
}

/// `floor(travel / dP)` as a 20-bit counter value from `start`.
fn expected(wheel: &Wheel<f64>, travel: f64, start: u32) -> u32 {
    let c = wheel.counts_for(travel).floor() as i64;
    ((i64::from(start) + c).rem_euclid(1 << 20)) as u32
}

#[test]
fn encoder_counts_follow_true_travel_forward_and_reverse() {
    let wheel = Wheel::new(500, 3.7, 0.05);
    let mut enc = Encoder::new(wheel).unwrap();
    let mut r = rng(1);
    let mut travel = 0.0;
    for i in 0..2000 {
        // Forward for a while, then back past zero.
        let delta = if i < 1000 { 0.0013 } else { -0.0021 };
        travel += delta;
        enc.set_travel(travel, &mut r).unwrap();
        assert_eq!(enc.read(), expected(&wheel, travel, 0), "step {i}");
    }
    assert!(travel < 0.0);
    assert_eq!(enc.decoder().invalid_transitions(), 0);
}

#[test]
fn encoder_wraps_at_20_bits() {
    let wheel = Wheel::<f64>::assumed();
    let start = (1 << 20) - 37;
    let mut enc = Encoder::new(wheel).unwrap().with_initial_count(start);
    let mut r = rng(2);
    let before = enc.read();
    let step = wheel.quantum() * 7.3;
    for _ in 0..20 {
        enc.advance(step, &mut r).unwrap();
    }
    assert_eq!(enc.read(), expected(&wheel, enc.travel(), start));
    assert!(enc.read() < start, "wrapped");
    let moved = wrapping_diff(enc.read(), before, 20);
    assert_eq!(
        i64::from(moved),
        wheel.counts_for(enc.travel()).floor() as i64
    );
    // And back down through the wrap.
    for _ in 0..40 {
        enc.advance(-step, &mut r).unwrap();
    }
    assert_eq!(enc.read(), expected(&wheel, enc.travel(), start));
}

#[test]
fn encoder_full_revolutions_from_zero_wrap() {
    // More than 2^20 counts from zero: 600 revolutions of 2000 counts.
    let wheel = Wheel::<f64>::assumed();
    let mut enc = Encoder::new(wheel).unwrap();
    let mut r = rng(3);
    let rev = 2.0 * core::f64::consts::PI * 0.05;
    for _ in 0..600 {
        enc.advance(rev, &mut r).unwrap();
    }
    assert_eq!(enc.read(), expected(&wheel, enc.travel(), 0));
}

#[test]
fn glitches_never_count() {
    let wheel = Wheel::<f64>::assumed();
    let mut enc = Encoder::new(wheel)
        .unwrap()
        .with_glitch_probability(0.5)
        .unwrap();
    let mut r = rng(4);
    let mut travel = 0.0;
    for i in 0..5000 {
        travel += if i % 700 < 400 { 0.00037 } else { -0.00051 };
        enc.set_travel(travel, &mut r).unwrap();
        assert_eq!(enc.read(), expected(&wheel, travel, 0), "step {i}");
    }
    assert!(enc.glitches() > 2000);
    assert_eq!(
        u64::from(enc.decoder().invalid_transitions()),
        2 * enc.glitches()
    );
    assert!(
        Encoder::new(wheel)
            .unwrap()
            .with_glitch_probability(1.5)
            .is_err()
    );
    assert!(enc.set_travel(f64::NAN, &mut r).is_err());
}

#[test]
fn ir_curve_round_trips() {
    let s = SharpIr::assumed(0.0).unwrap();
    for i in 0..=260 {
        let d = 0.04 + f64::from(i) * 0.001;
        let a = s.raw_from_distance(d);
        assert!(a > 80.0 && a < 600.0, "raw {a} at {d}");
        assert!((s.distance_from_raw(a) - d).abs() < 1e-12);
    }
    // Closer is a larger reading.
    assert!(s.raw_from_distance(0.05) > s.raw_from_distance(0.25));
    let mut r = rng(5);
    assert!(s.read(0.31, &mut r).is_none());
    assert!(s.read(0.03, &mut r).is_none());
    // The distance is reported as the nearest 32-bit float.
    assert_eq!(s.read(0.2, &mut r).unwrap(), f64::from(0.2f32));
    assert!(SharpIr::assumed(-1.0).is_err());
}

/// How far a reading of at most 0.3 m reported as a 32-bit float is from
/// the distance (m): half a unit in the last place, at most.
const F32_READING: f64 = 0.5 * 0.3 * f32::EPSILON as f64;

fn wall_x(w: f64) -> Vec<Segment<f64>> {
    vec![Segment::new([w, -1.0], [w, 1.0])]
}

#[test]
fn ir_pair_reads_distance_to_wall() {
    let pair = IrPairSensor::new(IrPair::centred(0.10), SharpIr::assumed(0.0).unwrap()).unwrap();
    let walls = wall_x(1.0);
    let mut r = rng(6);
    // Heading +y: the right side faces +x.
    let pose = [0.85, 0.0, core::f64::consts::FRAC_PI_2];
    let (d1, d2) = pair.read(&walls, pose, &mut r).unwrap().unwrap();
    assert_eq!((d1, d2), (f64::from(0.15f32), f64::from(0.15f32)));
    // Beyond 0.30 m: no observation.
    assert!(
        pair.read(&walls, [0.65, 0.0, pose[2]], &mut r)
            .unwrap()
            .is_none()
    );
    // Facing away: nothing.
    assert!(
        pair.read(&walls, [0.85, 0.0, -pose[2]], &mut r)
            .unwrap()
            .is_none()
    );
    // Rotated away from the wall (ccw): s1 reads more, and the model's
    // angle and distance recover the geometry.
    let turn = 0.1;
    let (d1, d2) = pair
        .read(&walls, [0.85, 0.0, pose[2] + turn], &mut r)
        .unwrap()
        .unwrap();
    assert!(d1 > d2);
    let (ang, dist) = pair.pair.angle_and_distance(d1, d2);
    // To the readings' 32-bit rounding: each reading within F32_READING,
    // so the angle within 2 F32_READING / L.
    assert!((ang - turn).abs() <= 2.0 * F32_READING / 0.1, "{ang}");
    assert!((dist - 0.15).abs() <= 2.0 * F32_READING, "{dist}");
}

#[test]
fn ir_pair_offsets() {
    let mount = IrPair {
        spacing: 0.1,
        lateral_offset: 0.05,
        forward_offset: 0.02,
    };
    let pair = IrPairSensor::new(mount, SharpIr::assumed(0.0).unwrap()).unwrap();
    let walls = wall_x(1.0);
    let mut r = rng(7);
    let turn = -0.2;
    let (d1, d2) = pair
        .read(
            &walls,
            [0.8, 0.0, core::f64::consts::FRAC_PI_2 + turn],
            &mut r,
        )
        .unwrap()
        .unwrap();
    let (ang, dist) = pair.pair.angle_and_distance(d1, d2);
    assert!((ang - turn).abs() <= 2.0 * F32_READING / 0.1, "{ang}");
    assert!((dist - 0.2).abs() <= 2.0 * F32_READING, "{dist}");
}

#[test]
fn laser_exact_without_noise() {
    let walls = vec![
        Segment::new([2.0, -1.0], [2.0, 1.0]),
        Segment::new([-1.0, 3.0], [1.0, 3.0]),
    ];
    let beams = vec![
        LaserMount::new(0.17, 0.0, 0.0),
        LaserMount::new(0.0, 0.1, core::f64::consts::FRAC_PI_2),
        LaserMount::new(0.0, 0.0, core::f64::consts::PI),
    ];
    let laser = Laser::new(beams, 0.0, 8.0).unwrap();
    let mut r = rng(8);
    let z = laser.read(&walls, [0.5, 0.0, 0.0], &mut r).unwrap();
    assert!((z[0].unwrap() - (2.0 - 0.67)).abs() < 1e-12);
    assert!((z[1].unwrap() - 2.9).abs() < 1e-12);
    assert!(z[2].is_none());
    // Out of range.
    let short = Laser::new(laser.beams.clone(), 0.0, 1.0).unwrap();
    let z = short.read(&walls, [0.5, 0.0, 0.0], &mut r).unwrap();
    assert_eq!(z, vec![None, None, None]);
    assert!(laser.read(&walls, [f64::NAN, 0.0, 0.0], &mut r).is_err());
}

#[test]
fn same_seed_same_readings() {
    let walls = wall_x(1.0);
    let run = |seed: u64| {
        let mut r = rng(seed);
        let ir = IrPairSensor::new(IrPair::centred(0.1), SharpIr::assumed(0.02).unwrap()).unwrap();
        let laser = Laser::new(vec![LaserMount::new(0.17, 0.0, 0.0)], 0.01, 8.0).unwrap();
        let mut enc = Encoder::new(Wheel::assumed())
            .unwrap()
            .with_glitch_probability(0.1)
            .unwrap();
        let mut out = Vec::new();
        for i in 0..200 {
            let x = 0.8 + 0.0005 * f64::from(i);
            let ir_z = ir
                .read(&walls, [x, 0.0, core::f64::consts::FRAC_PI_2], &mut r)
                .unwrap();
            let l = laser.read(&walls, [0.0, 0.0, 0.0], &mut r).unwrap();
            enc.advance(r.random_range(-0.01..0.02), &mut r).unwrap();
            out.push((ir_z, l, enc.read(), enc.glitches()));
        }
        out
    };
    assert_eq!(run(42), run(42));
    assert_ne!(run(42), run(43));
}
