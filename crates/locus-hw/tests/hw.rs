//! The cycle-level model of the papers' correction core (papers 000/003,
//! spec section 1): its f32 arithmetic against the software f32 plain-form
//! correction, its cycle count against a hand count, and the operators it
//! needs against the papers' 9 adders, 9 multipliers and 4 dividers.

use locus_core::nalgebra::{Matrix3, Vector3};
use locus_core::{Belief, CovarianceUpdate, Ekf, MeasurementModel};
use locus_hw::{self as hw, CoreInputs, HwConfig, Latencies, OpCounts, Schedule, State};
use locus_models::{LaserMount, LaserWallPaper, WallLine};

/// Deterministic pseudo-random numbers in [-1, 1) (a 64-bit LCG).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
}

/// Paper 000's laser model (the core's n = 3, m = 2 case) at a random prior.
fn case(
    rng: &mut Lcg,
) -> (
    Belief<f32, 3>,
    LaserWallPaper<f32>,
    locus_core::nalgebra::Vector2<f32>,
) {
    let model = LaserWallPaper::new(
        LaserMount::<f32>::paper_000(),
        WallLine::paper_000(1.17f32),
        1e-4 * (1.0 + 0.5 * rng.next()),
        2e-4 * (1.0 + 0.5 * rng.next()),
    );
    let x = Vector3::new(0.05 * rng.next(), 0.05 * rng.next(), 0.05 * rng.next());
    // A random SPD prior: L L^T + diag.
    let l = Matrix3::from_fn(|_, _| 0.05 * rng.next());
    let p = l * l.transpose() + Matrix3::from_diagonal(&Vector3::new(1e-3, 1e-3, 2e-4));
    let z = model.z_from_range(1.0 + 0.02 * rng.next());
    (Belief::new(x, p), model, z)
}

fn inputs(
    b: &Belief<f32, 3>,
    m: &LaserWallPaper<f32>,
    z: &locus_core::nalgebra::Vector2<f32>,
) -> CoreInputs {
    CoreInputs {
        x: b.x,
        p: b.p,
        h: m.jacobian(&b.x),
        r: m.noise(&b.x),
        z: *z,
        hx: m.h(&b.x).expect("the beam hits the wall"),
    }
}

fn rel<const R: usize, const C: usize>(
    a: &locus_core::nalgebra::SMatrix<f32, R, C>,
    b: &locus_core::nalgebra::SMatrix<f32, R, C>,
) -> f32 {
    (a - b).amax() / b.amax()
}

#[test]
fn f32_result_equals_the_software_f32_plain_correction() {
    let ekf = Ekf::<f32>::new(CovarianceUpdate::Plain);
    let cfg = HwConfig::default();
    let mut rng = Lcg(7);
    let (mut worst_x, mut worst_p, mut worst_sx, mut worst_sp) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for _ in 0..1000 {
        let (b, m, z) = case(&mut rng);
        let inp = inputs(&b, &m, &z);
        // The 11-step schedule against the generic plain-form correction.
        let sw = ekf.correct(&b, &m, &z).unwrap().belief;
        let core = hw::run(&cfg, Schedule::Inverse2x2, &inp).unwrap();
        // Compare the corrections X+ - X- (not X+ itself, whose size says
        // nothing about the update's accuracy) and P+.
        worst_x = worst_x.max(rel(&(core.x_post - b.x), &(sw.x - b.x)));
        worst_p = worst_p.max(rel(&core.p_post, &sw.p));
        // Scalar updates against the generic sequential plain correction.
        let sw = ekf.correct_sequential(&b, &m, &z).unwrap().belief;
        let core = hw::run(&cfg, Schedule::Scalar, &inp).unwrap();
        worst_sx = worst_sx.max(rel(&(core.x_post - b.x), &(sw.x - b.x)));
        worst_sp = worst_sp.max(rel(&core.p_post, &sw.p));
    }
    println!(
        "hw vs software f32, 1000 corrections: 11-step x {worst_x:.2e} P {worst_p:.2e}; scalar x {worst_sx:.2e} P {worst_sp:.2e}"
    );
    for w in [worst_x, worst_p, worst_sx, worst_sp] {
        assert!(w <= 1e-5, "relative difference {w:e}");
    }
}

#[test]
fn the_papers_core_needs_9_multipliers_9_adders_4_dividers() {
    let mut rng = Lcg(1);
    let (b, m, z) = case(&mut rng);
    let inp = inputs(&b, &m, &z);
    let run = hw::run(&HwConfig::default(), Schedule::Inverse2x2, &inp).unwrap();
    // 3x3 steps (9, 10, 11) keep all 9 datapaths busy; the inverse's four
    // divisions run at once.
    assert_eq!(
        run.operators,
        OpCounts {
            mul: 9,
            add: 9,
            div: 4
        }
    );
    // Operations executed: products 18+12+0+2+12+6+0+18+27 = 95 (steps 1, 2,
    // 4, 5, 7, 9, 10), additions 12+8+4+1+6+2+3+3+9+18+9 = 75 (steps 1..11,
    // the determinant in step 4), divisions 4.
    assert_eq!(
        run.operations,
        OpCounts {
            mul: 95,
            add: 75,
            div: 4
        }
    );
    // Fewer datapaths: fewer operators, more cycles.
    let small = HwConfig {
        datapaths: 3,
        ..HwConfig::default()
    };
    let r3 = hw::run(&small, Schedule::Inverse2x2, &inp).unwrap();
    assert_eq!(
        r3.operators,
        OpCounts {
            mul: 3,
            add: 3,
            div: 3
        }
    );
    assert!(r3.cycles > run.cycles);
    // Scalar updates divide 3 gain entries at once and never invert.
    let rs = hw::run(&HwConfig::default(), Schedule::Scalar, &inp).unwrap();
    assert_eq!(
        rs.operators,
        OpCounts {
            mul: 9,
            add: 9,
            div: 3
        }
    );
}

#[test]
fn cycle_count_matches_a_hand_count() {
    let mut rng = Lcg(3);
    let (b, m, z) = case(&mut rng);
    let run = hw::run(
        &HwConfig::default(),
        Schedule::Inverse2x2,
        &inputs(&b, &m, &z),
    )
    .unwrap();
    // L_mul 5, L_add 7, L_div 6, +1 per state visit, 9 datapaths (one wave
    // per step). dot3 = mult1 6 + mult2 2 + multadd 15 = 23; dot2 = 6+2+8 =
    // 16; add = 8; inverse = det (6+2+8) + div 7 = 23; waiting 2.
    // Steps 1..11: 23+23+8+23+16+8+16+8+16+23+8 = 172, + 2.
    assert_eq!(run.cycles, 174);
    assert!((run.time_s - 174.0 / 50e6).abs() < 1e-15);
    let per_state: u64 = run.cycles_per_state().iter().map(|(_, c)| c).sum();
    assert_eq!(per_state, run.cycles);
    assert_eq!(run.cycles_per_state()[0], (State::Waiting, 2));
    // One pipelined divider: the four divisions enter it one a cycle, so
    // div1 takes L_div + 3 (+1), three cycles more; 2 dividers, one more.
    for (dividers, cycles) in [(1, 177), (2, 175), (3, 175), (4, 174)] {
        let cfg = HwConfig {
            dividers,
            ..HwConfig::default()
        };
        let r = hw::run(&cfg, Schedule::Inverse2x2, &inputs(&b, &m, &z)).unwrap();
        assert_eq!(r.cycles, cycles, "{dividers} dividers");
        assert_eq!(
            (r.x_post, r.p_post, r.gain),
            (run.x_post, run.p_post, run.gain)
        );
        assert_eq!(r.operators.div, dividers);
    }
    // Slower operators cost more cycles; one datapath costs most.
    let slow = HwConfig {
        latencies: Latencies::ALTFP_SLOWEST,
        ..HwConfig::default()
    };
    let rs = hw::run(&slow, Schedule::Inverse2x2, &inputs(&b, &m, &z)).unwrap();
    assert!(rs.cycles > run.cycles);
    let mut last = u64::MAX;
    for d in 1..=9 {
        let cfg = HwConfig {
            datapaths: d,
            ..HwConfig::default()
        };
        let c = hw::run(&cfg, Schedule::Inverse2x2, &inputs(&b, &m, &z))
            .unwrap()
            .cycles;
        assert!(c <= last, "{d} datapaths: {c} cycles after {last}");
        last = c;
    }
}

#[test]
fn invalid_configuration_and_singular_innovation_are_errors() {
    let mut rng = Lcg(5);
    let (b, m, z) = case(&mut rng);
    let mut inp = inputs(&b, &m, &z);
    let cfg = HwConfig {
        datapaths: 0,
        ..HwConfig::default()
    };
    assert!(hw::run(&cfg, Schedule::Inverse2x2, &inp).is_err());
    inp.p = Matrix3::zeros();
    inp.r = locus_core::nalgebra::Matrix2::zeros();
    assert!(hw::run(&HwConfig::default(), Schedule::Inverse2x2, &inp).is_err());
    assert!(hw::run(&HwConfig::default(), Schedule::Scalar, &inp).is_err());
}
