//! One predict and one correct per model, in ns, in one run (f64, Joseph
//! update, through the generic `locus_core::Ekf` API).
//!
//! `cargo bench -p locus-models --bench models`

use core::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use locus_core::nalgebra::{Matrix3, SVector, Vector2, Vector3};
use locus_core::{Belief, Ekf, MeasurementModel, MotionModel};
use locus_models::camera::{nominal_pose, paper_q};
use locus_models::{
    AxisWall, CameraMarks4, ContinuousObserver, DiffDrive, FrontReading, IrPair, IrPairObservation,
    LaserMount, LaserRange, LaserWallPaper, ObserverState, RandomWalk6, RangeBearing, RearCounts,
    Segment, SkidSteer, TreadSpeeds, TricycleFront, TricycleRear, Unicycle, Velocities, WallLine,
    WheelTravel,
};

fn belief3(x: Vector3<f64>) -> Belief<f64, 3> {
    Belief::new(x, Matrix3::from_diagonal(&Vector3::new(1e-3, 2e-3, 1e-3)))
}

fn predict<Mo: MotionModel<f64, N, NQ>, const N: usize, const NQ: usize>(
    c: &mut Criterion,
    name: &str,
    b: Belief<f64, N>,
    model: Mo,
    u: Mo::Input,
) {
    let ekf = Ekf::default();
    ekf.predict(&b, &model, &u).expect("valid predict");
    c.bench_function(&format!("predict/{name}"), |bench| {
        bench.iter(|| ekf.predict(black_box(&b), black_box(&model), black_box(&u)))
    });
}

fn correct<Me: MeasurementModel<f64, N, M>, const N: usize, const M: usize>(
    c: &mut Criterion,
    name: &str,
    b: Belief<f64, N>,
    model: Me,
    z: SVector<f64, M>,
) {
    let ekf = Ekf::default();
    assert!(ekf.correct(&b, &model, &z).expect("valid correct").applied);
    c.bench_function(&format!("correct/{name}"), |bench| {
        bench.iter(|| ekf.correct(black_box(&b), black_box(&model), black_box(&z)))
    });
}

const MAP: [Segment<f64>; 4] = [
    Segment::new([1.0, -1.0], [1.0, 1.0]),
    Segment::new([1.0, 1.0], [-1.0, 1.0]),
    Segment::new([-1.0, 1.0], [-1.0, -1.0]),
    Segment::new([-1.0, -1.0], [1.0, -1.0]),
];

fn models(c: &mut Criterion) {
    // Paper 001.
    let b = belief3(Vector3::new(0.85, 0.0, core::f64::consts::FRAC_PI_2));
    predict(
        c,
        "001 diff drive",
        b,
        DiffDrive::new(0.12, 1e-6, 4e-4),
        WheelTravel {
            d1: 0.011,
            d2: 0.01,
        },
    );
    let ir = IrPairObservation {
        pair: IrPair::centred(0.10),
        wall: AxisWall::x_plus(1.0),
        ds1: 0.152,
        ds2: 0.148,
        r11: 2.5e-5,
        r22: 2.5e-5,
    };
    correct(c, "001 IR pair (2-D)", b, ir, ir.z());

    // Paper 000.
    let b0 = belief3(Vector3::new(0.0, 0.0, 0.0));
    predict(
        c,
        "000 skid steer",
        b0,
        SkidSteer::pioneer_3at(1e-4, 1e-4),
        TreadSpeeds::new(0.1, 0.1, 0.1),
    );
    let paper = LaserWallPaper::new(
        LaserMount::paper_000(),
        WallLine::paper_000(1.17),
        1e-4,
        1e-4,
    );
    let z = paper.h(&b0.x).unwrap() + Vector2::new(0.01, 0.0);
    correct(c, "000 laser, paper H (2-D)", b0, paper, z);
    let exact = LaserRange::new(LaserMount::paper_000(), &MAP, 1e-4);
    let z = exact.h(&b0.x).unwrap().add_scalar(0.01);
    correct(c, "000 laser, exact range to 4-segment map", b0, exact, z);

    // Paper 004.
    predict(
        c,
        "004 tricycle rear",
        b0,
        TricycleRear::assumed(),
        RearCounts::from_counts(120, 130),
    );
    predict(
        c,
        "004 tricycle front",
        b0,
        TricycleFront::assumed(),
        FrontReading::from_count(100, 0.2),
    );

    // Recorded logs.
    predict(
        c,
        "logs unicycle",
        b0,
        Unicycle::new(1e-4, 1e-3),
        Velocities {
            v: 0.2,
            omega: 0.3,
            dt: 0.02,
        },
    );
    let rb = RangeBearing::new(Vector2::new(2.0, 1.0), Vector2::new(0.05, 0.0), 0.05, 0.02);
    let z = rb.h(&b0.x).unwrap() + Vector2::new(0.02, 0.01);
    correct(c, "logs range-bearing", b0, rb, z);

    // Paper 002 (6-DOF, 8-D measurement).
    let b6 = Belief::new(nominal_pose::<f64>(), paper_q::<f64>() * 0.0051);
    predict(
        c,
        "002 random walk 6-DOF",
        b6,
        RandomWalk6::default(),
        0.005,
    );
    let cam = CameraMarks4::<f64>::paper_002();
    let z = cam.h(&b6.x).unwrap().add_scalar(1.0);
    correct(c, "002 camera, 4 marks (8-D)", b6, cam, z);
    let obs = ContinuousObserver::paper_002(50.0).unwrap();
    let mut x0 = nominal_pose::<f64>();
    x0.add_scalar_mut(0.05);
    let st = ObserverState::new(x0, paper_q::<f64>() * 0.0051);
    let y = cam.h(&nominal_pose()).unwrap();
    obs.step(&st, &cam, &y).unwrap();
    c.bench_function("observer step/002 continuous observer (dt 5 ms)", |bench| {
        bench.iter(|| obs.step(black_box(&st), black_box(&cam), black_box(&y)))
    });
}

fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(core::time::Duration::from_millis(500))
        .measurement_time(core::time::Duration::from_secs(2))
}

criterion_group! { name = benches; config = config(); targets = models }
criterion_main!(benches);
