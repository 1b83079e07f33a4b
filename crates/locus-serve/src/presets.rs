//! The teaching guide's steps a) to f) (paper 001 section VII.B, spec
//! section 3) as presets of the page, each with its criterion and a live
//! figure measured on the session's run.
//!
//! The configurations are those of `locus guide`
//! ([`locus_sim::guide::step_config`], on the served scenario): no gate,
//! IR noise of [`locus_sim::guide::IR_NOISE`] from step c on, `R` and `Q`
//! from [`locus_sim::guide::R_TINY`], [`locus_sim::guide::Q_TINY`],
//! [`locus_sim::guide::Q_HUGE`]. `locus guide` judges each step over 10 seeds;
//! the page shows the same figure for the one run being watched, so a
//! live verdict can differ from the guide's on an unlucky seed.

use locus_sim::SquareConfig;
use serde::Serialize;

/// One preset as the page lists it.
#[derive(Debug, Clone, Serialize)]
pub struct Preset {
    /// The step's letter (`a` to `f`).
    pub step: char,
    /// The configuration, in words.
    pub setup: &'static str,
    /// What the step demonstrates.
    pub demonstrates: &'static str,
    /// The criterion of spec section 3.
    pub criterion: &'static str,
}

/// The six presets.
pub const PRESETS: [Preset; 6] = [
    Preset {
        step: 'a',
        setup: "odometry only (IR unused)",
        demonstrates: "the covariance grows without bound; the robot gets lost",
        criterion: "det P never falls; trace(P_xy) ends > 10x its value after the first side",
    },
    Preset {
        step: 'b',
        setup: "noise-free IR, R tiny (1e-8 m^2)",
        demonstrates: "\"direct\" localisation works, only because the IR is perfect",
        criterion: "position RMSE < 1 cm",
    },
    Preset {
        step: 'c',
        setup: "IR noise 2 cm, R still tiny",
        demonstrates: "the estimate follows the IR noise",
        criterion: "RMSE >= 2x b's",
    },
    Preset {
        step: 'd',
        setup: "R = injected noise (4e-4 m^2), Q tiny (1e-14)",
        demonstrates: "the measurements are ignored: odometry only",
        criterion: "final error within 20 % of a's; mean position gain < 0.05",
    },
    Preset {
        step: 'e',
        setup: "R = injected noise, Q huge (1, 1e4)",
        demonstrates: "the filter jumps to each measurement, like b) and c)",
        criterion: "mean gain on the measured wall coordinate >= 0.9; RMSE >= c's",
    },
    Preset {
        step: 'f',
        setup: "R = injected noise, Q of the defaults, 99 % gate",
        demonstrates: "tuned Q and R give the best estimate, and a consistent one",
        criterion: "RMSE below c's, d's and e's",
    },
];

/// Running figures of one run, enough for every step's criterion.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct RunFigures {
    /// Steps so far.
    pub steps: usize,
    /// Position RMSE so far (m).
    pub rmse: f64,
    /// Position error at the last step (m).
    pub final_error: f64,
    /// Mean of `H K`'s position entry over the associated readings (NaN
    /// before the first).
    pub mean_gain: f64,
    /// Steps where `det P` fell (relative 1e-9).
    pub det_decreases: usize,
    /// Trace of the position covariance after the first side (m^2), once
    /// reached.
    pub trace_first_side: Option<f64>,
    /// Trace of the position covariance now (m^2).
    pub trace: f64,
    #[serde(skip)]
    sq_sum: f64,
    #[serde(skip)]
    gain_sum: f64,
    #[serde(skip)]
    gains: usize,
    /// The covariance of the previous step, for step a)'s `det P` test.
    #[serde(skip)]
    last_cov: Option<[[f64; 3]; 3]>,
}

/// Steps of the first side of the square at `V_ref`: side 1.7 m.
fn first_side_steps(cfg: &SquareConfig) -> usize {
    let side = 2.0 * locus_control::SQUARE_HALF_SIDE;
    let steps = (side / cfg.control.v_ref / cfg.dt).round();
    if steps.is_finite() && steps >= 1.0 {
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let s = steps as usize;
        s
    } else {
        1
    }
}

impl RunFigures {
    /// Adds one step's record.
    #[allow(clippy::cast_precision_loss)]
    pub fn push(&mut self, r: &locus_sim::StepRecord, cfg: &SquareConfig) {
        let p = r.ekf_cov;
        let e = (r.truth.x - r.ekf[0]).hypot(r.truth.y - r.ekf[1]);
        self.steps += 1;
        self.sq_sum += e * e;
        self.rmse = (self.sq_sum / self.steps as f64).sqrt();
        self.final_error = e;
        if let Some(g) = r.gain {
            self.gain_sum += g[0];
            self.gains += 1;
        }
        self.mean_gain = if self.gains > 0 {
            self.gain_sum / self.gains as f64
        } else {
            f64::NAN
        };
        if let Some(last) = &self.last_cov
            && locus_sim::guide::det_fell(last, &p)
        {
            self.det_decreases += 1;
        }
        self.last_cov = Some(p);
        self.trace = p[0][0] + p[1][1];
        if self.steps == first_side_steps(cfg) {
            self.trace_first_side = Some(self.trace);
        }
    }
}

/// A preset's criterion against the live run: the figure in words and the
/// verdict (`None` while it cannot be judged yet, e.g. before the first
/// side, or when it compares with a step not yet run in this session).
#[derive(Debug, Clone, Serialize)]
pub struct LiveFigure {
    /// The step's letter.
    pub step: char,
    /// The criterion.
    pub criterion: &'static str,
    /// The figure measured on this run.
    pub measured: String,
    /// The verdict so far.
    pub ok: Option<bool>,
}

/// Step `step`'s figure for `now`, with the figures of the steps already
/// run in the session (`others[i]` for step `'a' + i`); `finished`: the
/// run has ended (step a's criterion is about the end of the run, so its
/// verdict waits for it).
#[must_use]
#[allow(clippy::too_many_lines)]
pub fn live_figure(
    step: char,
    now: &RunFigures,
    others: &[Option<RunFigures>; 6],
    finished: bool,
) -> LiveFigure {
    let cm = |v: f64| 100.0 * v;
    let other = |c: char| {
        let i = (c as usize).wrapping_sub('a' as usize);
        others.get(i).copied().flatten()
    };
    let criterion = PRESETS
        .iter()
        .find(|p| p.step == step)
        .map_or("", |p| p.criterion);
    let (measured, ok) = match step {
        'a' => match now.trace_first_side {
            Some(t1) => {
                let growth = now.trace / t1;
                (
                    format!(
                        "det P fell at {} steps; trace(P_xy) now {growth:.1}x its value after side 1{}",
                        now.det_decreases,
                        if finished {
                            " (end of run)"
                        } else {
                            " (judged at the end)"
                        }
                    ),
                    if now.det_decreases > 0 {
                        Some(false)
                    } else {
                        finished.then_some(growth > 10.0)
                    },
                )
            }
            None => (
                format!(
                    "det P fell at {} steps; side 1 not done yet",
                    now.det_decreases
                ),
                None,
            ),
        },
        'b' => (
            format!("position RMSE {:.2} cm", cm(now.rmse)),
            (now.steps > 0).then_some(now.rmse < 0.01),
        ),
        'c' => match other('b') {
            Some(b) => (
                format!(
                    "position RMSE {:.2} cm = {:.1}x b's {:.2} cm",
                    cm(now.rmse),
                    now.rmse / b.rmse,
                    cm(b.rmse)
                ),
                Some(now.rmse >= 2.0 * b.rmse),
            ),
            None => (
                format!("position RMSE {:.2} cm (run b to compare)", cm(now.rmse)),
                None,
            ),
        },
        'd' => {
            let gain_ok = now.mean_gain < 0.05;
            match other('a') {
                Some(a) => {
                    let off = (now.final_error - a.final_error).abs() / a.final_error;
                    (
                        format!(
                            "mean position gain {:.4}; error {:.1} cm vs a's {:.1} cm ({:.0} % off)",
                            now.mean_gain,
                            cm(now.final_error),
                            cm(a.final_error),
                            100.0 * off
                        ),
                        Some(gain_ok && off <= 0.2),
                    )
                }
                None => (
                    format!(
                        "mean position gain {:.4} (run a to compare the error)",
                        now.mean_gain
                    ),
                    None,
                ),
            }
        }
        'e' => {
            let gain_ok = now.mean_gain >= 0.9;
            match other('c') {
                Some(c) => (
                    format!(
                        "mean wall-coordinate gain {:.3}; RMSE {:.2} cm = {:.2}x c's {:.2} cm",
                        now.mean_gain,
                        cm(now.rmse),
                        now.rmse / c.rmse,
                        cm(c.rmse)
                    ),
                    Some(gain_ok && now.rmse >= c.rmse),
                ),
                None => (
                    format!(
                        "mean wall-coordinate gain {:.3} (run c to compare the RMSE)",
                        now.mean_gain
                    ),
                    None,
                ),
            }
        }
        'f' => {
            let best = ['c', 'd', 'e']
                .iter()
                .filter_map(|&c| other(c))
                .map(|r| r.rmse)
                .fold(f64::INFINITY, f64::min);
            let all = ['c', 'd', 'e'].iter().all(|&c| other(c).is_some());
            (
                if best.is_finite() {
                    format!(
                        "RMSE {:.2} cm (best of c, d, e run so far: {:.2} cm)",
                        cm(now.rmse),
                        cm(best)
                    )
                } else {
                    format!("RMSE {:.2} cm (run c, d, e to compare)", cm(now.rmse))
                },
                all.then_some(now.rmse < best),
            )
        }
        _ => (String::new(), None),
    };
    LiveFigure {
        step,
        criterion,
        measured,
        ok,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use locus_sim::guide::{IR_NOISE, Q_TINY, step_config as config};

    #[test]
    fn presets_are_the_guide_configurations() {
        let base = SquareConfig::default();
        let a = config('a', &base).unwrap();
        assert!(!a.use_ir && a.gate_confidence.is_none());
        let d = config('d', &base).unwrap();
        assert_eq!((d.q11, d.q22), Q_TINY);
        assert_eq!(d.ir_sigma, IR_NOISE);
        let f = config('f', &base).unwrap();
        assert_eq!(f.gate_confidence, Some(0.99));
        assert!(config('g', &base).is_none());
        for p in PRESETS {
            config(p.step, &base).unwrap().validate().unwrap();
        }
    }

    #[test]
    fn step_a_on_a_live_run_grows_its_covariance() {
        let cfg = config('a', &SquareConfig::default()).unwrap();
        let mut sim = locus_sim::SquareSim::new(&cfg, 1).unwrap();
        let mut fig = RunFigures::default();
        let mut pending = None;
        while let Some(s) = sim.step(None).unwrap() {
            fig.push(&s.record, &cfg);
            if s.record.step == 6000 {
                pending = Some(live_figure('a', &fig, &[None; 6], false));
            }
        }
        let pending = pending.unwrap();
        assert_eq!(pending.ok, None, "judged at the end: {}", pending.measured);
        let live = live_figure('a', &fig, &[None; 6], true);
        assert_eq!(live.ok, Some(true), "{}", live.measured);
    }
}
