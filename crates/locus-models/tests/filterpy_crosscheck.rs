//! Independent cross-check of the Locus EKF with the paper-001 and paper-000
//! models against filterpy (Python).
//!
//! The test runs `scripts/filterpy_crosscheck.py` (python from the environment
//! variable `LOCUS_PYTHON`, else `python3`; it needs numpy and filterpy:
//! `pip install -r scripts/requirements-crosscheck.txt`). The script implements
//! the differential-drive and IR-pair models independently from the spec
//! (MODELS.md section 3), runs filterpy's `ExtendedKalmanFilter` (Joseph form)
//! on two seeded 1000-step runs of the square arena (one with the sensors
//! centred, one with offsets e = 0.03 m, c = 0.02 m) and writes, per step, the
//! inputs and filterpy's posterior. This test replays the same inputs through
//! `locus_core::Ekf::default()` (Joseph) with `DiffDrive` and
//! `IrPairObservation`, and asserts at every step:
//!
//! * state: `|x - x_ref| <= 1e-9` (m), same for y, and
//!   `|wrap(theta - theta_ref)| <= 1e-9` (rad);
//! * covariance: `|P_ij - Pref_ij| <= 1e-9 * max(|P_ij|, |Pref_ij|, sqrt(Pref_ii Pref_jj))`;
//! * diagnostics (where an observation exists): the observation `z` with the
//!   same absolute tolerance as the state, and `V R V^T` with the same mixed
//!   tolerance as `P`.
//!
//! Why that covariance tolerance: the entries of P carry different units (m^2,
//! rad^2, m rad) and span several orders of magnitude, and off-diagonal entries
//! pass through zero, so neither a pure relative nor a single absolute tolerance
//! is meaningful. Rounding in a covariance computation scales with the
//! standard deviations involved: `|P_ij| <= sqrt(P_ii P_jj)` (Cauchy-Schwarz),
//! so the scale `sqrt(P_ii P_jj)` makes the test a relative 1e-9 bound on the
//! diagonal and a 1e-9 bound on the *correlation coefficient* off the diagonal,
//! in consistent units. The two implementations differ only by rounding
//! (filterpy inverts S with LAPACK and does not symmetrise P; Locus solves with
//! a Cholesky factor and symmetrises after predict), which is ~1e-15 relative,
//! so 1e-9 leaves a wide margin while any modelling difference (a sign, a
//! missing offset term, an unwrapped angle) shows up at 1e-4 or more.
//!
//! # Paper 000
//! A second test (`--only 000`) does the same for the paper-000 models
//! (MODELS.md section 2, implemented independently in the script): a seeded
//! 1000-step run of a Table III-like path (straight, turn to +47.5 deg,
//! straight, turn to 61.7 deg, straight, at 0.10 m/s and 0.3 rad/s, dT = 0.1 s,
//! 1 s at rest at each Table III instant, then back to the start and again;
//! slipping treads, noisy encoders, a laser range to the wall x + y = 1.17 m
//! with a smaller noise at rest than in motion), filtered twice on the same
//! inputs: `run3_000_paper.csv` corrects with the paper's `H` (`z = [u_i, v_i]`,
//! `LaserWallPaper`), `run4_000_range.csv` with the exact range model
//! (`z = [gamma]`, `LaserRange`). Locus replays `SkidSteer` predictions and the
//! run's laser model and asserts, at every step, that it predicts a measurement
//! exactly where the script did (`pred_valid`), the same predicted measurement
//! `z_hat` (absolute 1e-9 m), and the posterior with the tolerances above.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use locus_core::nalgebra::{Matrix2, Matrix3, SVector, Vector2, Vector3};
use locus_core::{Belief, Ekf, MeasurementModel, wrap_angle};
use locus_models::laser_wall::{
    BeamLimits, LaserMount, LaserRange, LaserWallPaper, Segment, WallLine,
};
use locus_models::skid_steer::{SkidSteer, TreadSpeeds};
use locus_models::{AxisWall, DiffDrive, IrPair, IrPairObservation, WheelTravel};

/// Absolute tolerance on the state (m, m, rad) and on z.
const TOL_STATE: f64 = 1e-9;
/// Relative tolerance of the mixed covariance criterion (see the module doc).
const TOL_COV: f64 = 1e-9;
/// The runs the script writes.
const RUNS: [&str; 2] = ["run1_centred.csv", "run2_offset.csv"];

/// One parsed CSV: the initial belief and the rows, accessed by column name.
struct Run {
    init: Belief<f64, 3>,
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Run {
    fn col(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| {
                panic!(
                    "column {name:?} missing from the CSV header {:?}",
                    self.header
                )
            })
    }
}

struct Row<'a> {
    run: &'a Run,
    cells: &'a [String],
    line: usize,
}

impl Row<'_> {
    fn str(&self, name: &str) -> &str {
        &self.cells[self.run.col(name)]
    }
    fn f(&self, name: &str) -> f64 {
        let s = self.str(name);
        s.parse::<f64>().unwrap_or_else(|e| {
            panic!("line {}: column {name}: cannot parse {s:?}: {e}", self.line)
        })
    }
}

fn parse_f64s(s: &str, what: &str) -> Vec<f64> {
    s.split(',')
        .map(|v| {
            v.trim()
                .parse::<f64>()
                .unwrap_or_else(|e| panic!("{what}: cannot parse {v:?}: {e}"))
        })
        .collect()
}

fn parse_run(path: &Path) -> Run {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let mut lines = text.lines();
    let init_line = lines.next().expect("empty CSV");
    let init = init_line
        .strip_prefix("#init,")
        .unwrap_or_else(|| panic!("first line must start with '#init,': {init_line:?}"));
    let v = parse_f64s(init, "#init line");
    assert_eq!(
        v.len(),
        12,
        "#init line must hold x, y, theta and the 9 entries of P"
    );
    let init = Belief::new(
        Vector3::new(v[0], v[1], v[2]),
        Matrix3::from_row_slice(&v[3..12]),
    );
    let header: Vec<String> = lines
        .next()
        .expect("CSV without header")
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows: Vec<Vec<String>> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').map(str::to_owned).collect::<Vec<_>>())
        .collect();
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(
            r.len(),
            header.len(),
            "line {}: {} cells, header has {}",
            i + 3,
            r.len(),
            header.len()
        );
    }
    Run { init, header, rows }
}

fn wall_from(name: &str, lw: f64) -> AxisWall<f64> {
    match name {
        "x+" => AxisWall::x_plus(lw),
        "x-" => AxisWall::x_minus(lw),
        "y+" => AxisWall::y_plus(lw),
        "y-" => AxisWall::y_minus(lw),
        other => panic!("unknown wall {other:?}"),
    }
}

/// Largest discrepancies seen in one run.
#[derive(Default, Debug)]
struct Stats {
    steps: usize,
    observations: usize,
    /// max |x - x_ref|, |y - y_ref|, |wrap(theta - theta_ref)| (m, rad).
    state_abs: f64,
    /// max over P entries of |a - b| / max(|a|, |b|, sqrt(Pii Pjj)).
    cov_rel: f64,
    /// max over P entries of |a - b| (mixed units).
    cov_abs: f64,
    /// max |z - z_ref| (theta wrapped).
    z_abs: f64,
    /// max mixed-relative discrepancy of V R V^T.
    vrv_rel: f64,
}

/// `|a - b| / max(|a|, |b|, floor)`.
fn mixed_rel(a: f64, b: f64, floor: f64) -> f64 {
    let scale = a.abs().max(b.abs()).max(floor);
    if scale == 0.0 {
        (a - b).abs()
    } else {
        (a - b).abs() / scale
    }
}

fn replay(name: &str, run: &Run) -> Stats {
    let ekf = Ekf::<f64>::default();
    let mut belief = run.init;
    let mut st = Stats::default();
    for (i, cells) in run.rows.iter().enumerate() {
        let row = Row {
            run,
            cells,
            line: i + 3,
        };
        let step = row.str("step");
        let here = format!("{name}, step {step} (CSV line {})", row.line);

        // Predict.
        let model = DiffDrive::new(row.f("b"), row.f("Q11"), row.f("Q22"));
        let u = WheelTravel {
            d1: row.f("d1"),
            d2: row.f("d2"),
        };
        belief = ekf
            .predict(&belief, &model, &u)
            .unwrap_or_else(|e| panic!("{here}: Locus predict failed: {e:?}"));

        // Correct.
        match row.str("has_obs") {
            "0" => {}
            "1" => {
                let obs = IrPairObservation {
                    pair: IrPair {
                        spacing: row.f("L"),
                        lateral_offset: row.f("e"),
                        forward_offset: row.f("c"),
                    },
                    wall: wall_from(row.str("wall"), row.f("Lw")),
                    ds1: row.f("ds1"),
                    ds2: row.f("ds2"),
                    r11: row.f("R11"),
                    r22: row.f("R22"),
                };
                let z = obs.z();
                let z_ref = Vector2::new(row.f("z_pos"), row.f("z_theta"));
                let dz = [(z[0] - z_ref[0]).abs(), wrap_angle(z[1] - z_ref[1]).abs()];
                st.z_abs = st.z_abs.max(dz[0]).max(dz[1]);
                assert!(
                    dz[0] <= TOL_STATE && dz[1] <= TOL_STATE,
                    "{here}: observation z differs: Locus {z:?}, filterpy script {z_ref:?} (wall {})",
                    row.str("wall")
                );
                let vrv = obs.noise(&belief.x);
                let vrv_ref = Matrix2::new(
                    row.f("VRV00"),
                    row.f("VRV01"),
                    row.f("VRV01"),
                    row.f("VRV11"),
                );
                for r in 0..2 {
                    for c in 0..2 {
                        let floor = (vrv_ref[(r, r)] * vrv_ref[(c, c)]).abs().sqrt();
                        let d = mixed_rel(vrv[(r, c)], vrv_ref[(r, c)], floor);
                        st.vrv_rel = st.vrv_rel.max(d);
                        assert!(
                            d <= TOL_COV,
                            "{here}: V R V^T differs in ({r},{c}): Locus {vrv}, filterpy script {vrv_ref}"
                        );
                    }
                }
                let corr = ekf
                    .correct(&belief, &obs, &z)
                    .unwrap_or_else(|e| panic!("{here}: Locus correct failed: {e:?}"));
                assert!(
                    corr.applied,
                    "{here}: correction not applied (no gate is set)"
                );
                belief = corr.belief;
                st.observations += 1;
            }
            other => panic!("{here}: has_obs must be 0 or 1, got {other:?}"),
        }

        check_posterior(&here, &belief, &row, &mut st);
        st.steps += 1;
    }
    st
}

/// Compares Locus's posterior with filterpy's (the row's x, y, theta, P..)
/// with the tolerances of the module doc, and records the discrepancies.
fn check_posterior(here: &str, belief: &Belief<f64, 3>, row: &Row<'_>, st: &mut Stats) {
    let x_ref = Vector3::new(row.f("x"), row.f("y"), row.f("theta"));
    let dx = [
        (belief.x[0] - x_ref[0]).abs(),
        (belief.x[1] - x_ref[1]).abs(),
        wrap_angle(belief.x[2] - x_ref[2]).abs(),
    ];
    let worst = dx[0].max(dx[1]).max(dx[2]);
    st.state_abs = st.state_abs.max(worst);
    assert!(
        worst <= TOL_STATE,
        "{here}: state differs by {dx:?} (tolerance {TOL_STATE}):\n  Locus    {:?}\n  filterpy {:?}",
        belief.x.as_slice(),
        x_ref.as_slice()
    );
    let mut p_ref = Matrix3::zeros();
    for r in 0..3 {
        for c in 0..3 {
            p_ref[(r, c)] = row.f(&format!("P{r}{c}"));
        }
    }
    for r in 0..3 {
        for c in 0..3 {
            let (a, b) = (belief.p[(r, c)], p_ref[(r, c)]);
            let floor = (p_ref[(r, r)] * p_ref[(c, c)]).abs().sqrt();
            let d = mixed_rel(a, b, floor);
            st.cov_rel = st.cov_rel.max(d);
            st.cov_abs = st.cov_abs.max((a - b).abs());
            assert!(
                d <= TOL_COV,
                "{here}: P({r},{c}) differs: Locus {a:e}, filterpy {b:e}, |diff| / scale = {d:e} \
                 (tolerance {TOL_COV:e})\n  Locus P {}\n  filterpy P {}",
                belief.p,
                p_ref
            );
        }
    }
}

fn scratch_dir(tag: &str) -> PathBuf {
    let nanos = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    std::env::temp_dir().join(format!(
        "locus-filterpy-crosscheck-{tag}-{}-{nanos}",
        std::process::id()
    ))
}

/// Runs `scripts/filterpy_crosscheck.py --out DIR --only {only}` and returns
/// DIR (the reference CSVs).
fn run_script(only: &str) -> PathBuf {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/filterpy_crosscheck.py");
    assert!(
        script.is_file(),
        "cross-check script not found at {}",
        script.display()
    );
    let python = std::env::var("LOCUS_PYTHON").unwrap_or_else(|_| "python3".to_owned());
    let out_dir = scratch_dir(only);

    let output = Command::new(&python)
        .arg(&script)
        .arg("--out")
        .arg(&out_dir)
        .arg("--only")
        .arg(only)
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "cannot run {python:?} (set LOCUS_PYTHON to a Python 3 with numpy and filterpy; \
                 pip install -r scripts/requirements-crosscheck.txt): {e}"
            )
        });
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "the filterpy cross-check script failed ({}): {python} {} --out {} --only {only}\n--- stdout\n{stdout}\n--- stderr\n{stderr}\n\
         (needs numpy and filterpy: pip install -r scripts/requirements-crosscheck.txt; \
         or set LOCUS_PYTHON to the right interpreter)",
        output.status,
        script.display(),
        out_dir.display()
    );
    print!("{stdout}");
    println!(
        "reference CSVs in {} (removed if the test passes)",
        out_dir.display()
    );
    out_dir
}

#[test]
fn ekf_matches_filterpy_on_paper_001_runs() {
    let t0 = Instant::now();
    let out_dir = run_script("001");
    let t_python = t0.elapsed();

    for name in RUNS {
        let path = out_dir.join(name);
        let run = parse_run(&path);
        assert!(
            run.rows.len() >= 1000,
            "{name}: expected at least 1000 steps, got {}",
            run.rows.len()
        );
        let st = replay(name, &run);
        assert!(
            st.observations > 0,
            "{name}: no IR observation: the run does not exercise the correction"
        );
        println!(
            "{name}: {} steps, {} corrections; max |state diff| = {:.3e} (m/rad), \
             max P diff = {:.3e} relative (mixed scale) / {:.3e} absolute, \
             max |z diff| = {:.3e}, max V R V^T diff = {:.3e} relative",
            st.steps, st.observations, st.state_abs, st.cov_rel, st.cov_abs, st.z_abs, st.vrv_rel
        );
    }
    println!(
        "filterpy cross-check: script {:.2} s, total {:.2} s",
        t_python.as_secs_f64(),
        t0.elapsed().as_secs_f64()
    );
    // Only clean up on success: on failure the CSVs stay for inspection.
    let _ = std::fs::remove_dir_all(&out_dir);
}

// ---------------------------------------------------------------------------
// Paper 000: skid-steer prediction, laser correction with the paper's H and
// with the exact range model.
// ---------------------------------------------------------------------------

/// The runs of paper 000 the script writes, and the laser model of each.
const RUNS_000: [(&str, Laser000); 2] = [
    ("run3_000_paper.csv", Laser000::Paper),
    ("run4_000_range.csv", Laser000::Range),
];

/// Which laser model a paper-000 run corrects with.
#[derive(Debug, Clone, Copy)]
enum Laser000 {
    /// `LaserWallPaper`: z = [u_i, v_i], H with (l, m) held fixed.
    Paper,
    /// `LaserRange`: z = [gamma], exact H.
    Range,
}

fn flag(row: &Row<'_>, name: &str, here: &str) -> bool {
    match row.str(name) {
        "0" => false,
        "1" => true,
        other => panic!("{here}: {name} must be 0 or 1, got {other:?}"),
    }
}

/// One laser correction: checks that Locus predicts a measurement exactly
/// where the script did (`pred_valid`) and the same prediction (`zhat*`),
/// then applies the correction if the row has one (`has_obs`, `z*`).
fn laser_step<Me, const M: usize>(
    here: &str,
    ekf: &Ekf<f64>,
    belief: &Belief<f64, 3>,
    model: &Me,
    row: &Row<'_>,
    st: &mut Stats,
) -> Belief<f64, 3>
where
    Me: MeasurementModel<f64, 3, M>,
{
    let zhat = model.h(&belief.x);
    let pred_valid = flag(row, "pred_valid", here);
    assert_eq!(
        zhat.is_some(),
        pred_valid,
        "{here}: Locus {} a measurement at the prior {:?}, the script {}",
        if zhat.is_some() {
            "predicts"
        } else {
            "predicts no"
        },
        belief.x.as_slice(),
        if pred_valid { "does" } else { "does not" }
    );
    if let Some(zhat) = zhat {
        for k in 0..M {
            let d = (zhat[k] - row.f(&format!("zhat{k}"))).abs();
            st.z_abs = st.z_abs.max(d);
            assert!(
                d <= TOL_STATE,
                "{here}: predicted measurement differs: Locus {zhat:?}, script zhat{k} = {}",
                row.str(&format!("zhat{k}"))
            );
        }
    }
    if !flag(row, "has_obs", here) {
        return *belief;
    }
    let mut z = SVector::<f64, M>::zeros();
    for k in 0..M {
        z[k] = row.f(&format!("z{k}"));
    }
    let corr = ekf
        .correct(belief, model, &z)
        .unwrap_or_else(|e| panic!("{here}: Locus correct failed: {e:?}"));
    assert!(
        corr.applied,
        "{here}: correction not applied (no gate is set)"
    );
    st.observations += 1;
    corr.belief
}

fn replay_000(name: &str, run: &Run, variant: Laser000) -> Stats {
    let ekf = Ekf::<f64>::default();
    let mut belief = run.init;
    let mut st = Stats::default();
    for (i, cells) in run.rows.iter().enumerate() {
        let row = Row {
            run,
            cells,
            line: i + 3,
        };
        let here = format!("{name}, step {} (CSV line {})", row.str("step"), row.line);

        // Predict: skid steer, Euler.
        let motion = SkidSteer::new(row.f("D"), row.f("var_vl"), row.f("var_vr"));
        let u = TreadSpeeds::new(row.f("v_l"), row.f("v_r"), row.f("dt"));
        belief = ekf
            .predict(&belief, &motion, &u)
            .unwrap_or_else(|e| panic!("{here}: Locus predict failed: {e:?}"));

        // Correct: the run's laser model.
        let mount = LaserMount::new(row.f("x_si"), row.f("y_si"), row.f("beta"));
        let limits = BeamLimits {
            max_range: row.f("max_range"),
            parallel_tol: row.f("parallel_tol"),
        };
        belief = match variant {
            Laser000::Paper => {
                let wall = WallLine::new([row.f("nx"), row.f("ny")], [row.f("p0x"), row.f("p0y")]);
                let mut model = LaserWallPaper::new(mount, wall, row.f("R0"), row.f("R1"));
                model.limits = limits;
                laser_step(&here, &ekf, &belief, &model, &row, &mut st)
            }
            Laser000::Range => {
                let map = [Segment::new(
                    [row.f("ax"), row.f("ay")],
                    [row.f("bx"), row.f("by")],
                )];
                let mut model = LaserRange::new(mount, &map, row.f("R0"));
                model.limits = limits;
                laser_step(&here, &ekf, &belief, &model, &row, &mut st)
            }
        };

        check_posterior(&here, &belief, &row, &mut st);
        st.steps += 1;
    }
    st
}

#[test]
fn ekf_matches_filterpy_on_paper_000_runs() {
    let t0 = Instant::now();
    let out_dir = run_script("000");
    let t_python = t0.elapsed();

    for (name, variant) in RUNS_000 {
        let path = out_dir.join(name);
        let run = parse_run(&path);
        assert!(
            run.rows.len() >= 1000,
            "{name}: expected at least 1000 steps, got {}",
            run.rows.len()
        );
        let st = replay_000(name, &run, variant);
        assert!(
            st.observations > 0,
            "{name}: no laser observation: the run does not exercise the correction"
        );
        println!(
            "{name} ({variant:?} laser model): {} steps, {} corrections; max |state diff| = {:.3e} \
             (m/rad), max P diff = {:.3e} relative (mixed scale) / {:.3e} absolute, \
             max |z_hat diff| = {:.3e} m",
            st.steps, st.observations, st.state_abs, st.cov_rel, st.cov_abs, st.z_abs
        );
    }
    println!(
        "filterpy cross-check (000): script {:.2} s, total {:.2} s",
        t_python.as_secs_f64(),
        t0.elapsed().as_secs_f64()
    );
    // Only clean up on success: on failure the CSVs stay for inspection.
    let _ = std::fs::remove_dir_all(&out_dir);
}
