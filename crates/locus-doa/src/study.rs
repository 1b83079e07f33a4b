//! The sweep of paper 002's domain-of-attraction study: runs from the
//! vertices of the error hypercube, `phi(m)`, the `M_zeta` search and the
//! worst settling time, per cell of the grid (see the run rules in the
//! module `doa`).

use locus_core::nalgebra::{SMatrix, SVector};
use locus_core::{Error as CoreError, MeasurementModel};
use locus_models::camera::CameraMarks4;
use locus_models::observer::{ContinuousObserver, ObserverState};
use rayon::prelude::*;

use super::{DoaConfig, DoaError, DoaResult, SearchConfig, Shard};

/// Number of vertices of the 6-D error hypercube (`2^6`).
pub const VERTICES: usize = 64;

/// The initial error at vertex `v` (0..64) of the hypercube of half-width
/// `m`: component `i` is `-m` if bit `i` of `v` is set, else `+m`.
pub fn vertex(v: usize, m: f64) -> SVector<f64, 6> {
    SVector::<f64, 6>::from_fn(|i, _| if (v >> i) & 1 == 1 { -m } else { m })
}

/// Tracks the settling time along a run: the time after which the error
/// norm stays below the threshold (0 if it never reaches it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SettleTracker {
    threshold: f64,
    last_above: usize,
}

impl SettleTracker {
    /// A tracker for `threshold` (m or rad).
    pub fn new(threshold: f64) -> Self {
        Self {
            threshold,
            last_above: 0,
        }
    }

    /// Records the error norm after step `k` (1-based: the state at time
    /// `k dt`).
    pub fn observe(&mut self, k: usize, norm: f64) {
        // NaN counts as above.
        if norm.partial_cmp(&self.threshold) != Some(core::cmp::Ordering::Less) {
            self.last_above = k;
        }
    }

    /// The settling time (s): `dt` times the last step whose norm was not
    /// below the threshold (0 if none).
    pub fn settle_time(&self, dt: f64) -> f64 {
        self.last_above as f64 * dt
    }
}

/// Why a run diverged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Divergence {
    /// A mark came within `min_depth` of the camera plane (or behind it).
    MarkAtCameraPlane,
    /// A value became non-finite (overflow of the explicit integration).
    NonFinite,
}

/// The outcome of one run (see the run rules of the module [`doa`](super)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RunOutcome {
    /// Lasted the horizon with a final norm below the threshold.
    Converged {
        /// Settling time (s).
        settle: f64,
        /// Final error norm (m or rad).
        final_error: f64,
    },
    /// Lasted the horizon but the final norm is not below the threshold.
    NotConverged {
        /// Final error norm (m or rad).
        final_error: f64,
    },
    /// A step failed.
    Diverged {
        /// The step (0-based) that failed.
        step: usize,
        /// Why.
        reason: Divergence,
    },
}

impl RunOutcome {
    /// True for [`RunOutcome::Converged`].
    pub fn converged(&self) -> bool {
        matches!(self, Self::Converged { .. })
    }
}

/// The result of the `M_zeta` search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MZeta {
    /// `M_zeta`: the largest amplitude found with `phi = 1` (0 if none).
    pub value: f64,
    /// The first failing amplitude bounding it (`None` if every amplitude up
    /// to the cap passed).
    pub failure: Option<f64>,
    /// Number of `phi` evaluations.
    pub evaluations: u32,
}

/// `M_zeta` by stepping then bisecting (spec section 4): `phi` is tried at
/// `m_start + k m_step` (k = 0, 1, ...; up to `m_cap`) until it first fails;
/// then the bracket (last success or 0, first failure) is bisected until its
/// width is at most `tolerance`. Returns the bracket's lower end.
pub fn search_m_zeta(search: &SearchConfig, mut phi: impl FnMut(f64) -> bool) -> MZeta {
    let mut evaluations = 0;
    let mut eval = |m: f64| {
        evaluations += 1;
        phi(m)
    };
    let mut lo = 0.0;
    let mut hi = None;
    let mut k = 0usize;
    loop {
        let m = search.m_start + search.m_step * k as f64;
        if m > search.m_cap * (1.0 + 1e-12) {
            break;
        }
        if eval(m) {
            lo = m;
            k += 1;
        } else {
            hi = Some(m);
            break;
        }
    }
    if let Some(mut h) = hi {
        while h - lo > search.tolerance {
            let mid = 0.5 * (lo + h);
            if eval(mid) {
                lo = mid;
            } else {
                h = mid;
            }
        }
        hi = Some(h);
    }
    MZeta {
        value: lo,
        failure: hi,
        evaluations,
    }
}

/// One cell of the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    /// Row-major index `i_vg n_alpha + i_alpha`.
    pub index: usize,
    /// Row (`v_g`) index.
    pub i_vg: usize,
    /// Column (`alpha`) index.
    pub i_alpha: usize,
    /// `v_g` (`P0 = v_g Q`).
    pub v_g: f64,
    /// `alpha` (1/s).
    pub alpha: f64,
}

/// The result of one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellResult {
    /// The cell.
    pub cell: Cell,
    /// `M_zeta` (m, rad).
    pub m_zeta: f64,
    /// Number of `phi` evaluations of the search.
    pub evaluations: u32,
    /// Worst settling time over the 64 vertices at the settling amplitude
    /// (s); `None` if some vertex does not converge there.
    pub settle: Option<f64>,
}

/// A validated study: the model, the measurement and everything a run needs.
#[derive(Debug, Clone)]
pub struct Study {
    config: DoaConfig,
    model: CameraMarks4<f64>,
    nominal: SVector<f64, 6>,
    y: SVector<f64, 8>,
    q: SMatrix<f64, 6, 6>,
    theta: SMatrix<f64, 8, 8>,
    steps: usize,
}

impl Study {
    /// Validates the configuration and prepares the study.
    pub fn new(config: DoaConfig) -> Result<Self, DoaError> {
        config.validate()?;
        let model = config.model();
        let nominal = config.nominal();
        let y = model.h(&nominal).ok_or_else(|| DoaError::Invalid {
            file: "<config>".into(),
            line: 0,
            field: "geometry.nominal_pose".into(),
            message: "no measurement at the nominal pose".into(),
        })?;
        let q = config.noise_q();
        let theta = SMatrix::<f64, 8, 8>::identity()
            * (config.noise.pixel_sigma * config.noise.pixel_sigma);
        let steps = config.run.steps();
        Ok(Self {
            config,
            model,
            nominal,
            y,
            q,
            theta,
            steps,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &DoaConfig {
        &self.config
    }

    /// The observer for weighting `alpha` (1/s).
    pub fn observer(&self, alpha: f64) -> ContinuousObserver<f64, 6, 8> {
        ContinuousObserver::new(alpha, self.q, self.theta, self.config.run.dt)
            .expect("alpha, Q, Theta and dt were validated")
    }

    /// The cells of the grid in row-major order.
    pub fn cells(&self) -> impl Iterator<Item = Cell> + '_ {
        let g = &self.config.grid;
        (0..g.cells()).map(move |index| {
            let (i_vg, i_alpha) = (index / g.alpha_count, index % g.alpha_count);
            Cell {
                index,
                i_vg,
                i_alpha,
                v_g: g.v_g(i_vg),
                alpha: g.alpha(i_alpha),
            }
        })
    }

    /// One run from `x_n + zeta0` with `P0 = v_g Q`, classified by the run
    /// rules: it stops at the first failing step (divergence) and otherwise
    /// runs the whole horizon, since convergence is judged at the end.
    pub fn run(
        &self,
        observer: &ContinuousObserver<f64, 6, 8>,
        v_g: f64,
        zeta0: &SVector<f64, 6>,
    ) -> RunOutcome {
        let mut state = ObserverState::new(self.nominal + zeta0, self.q * v_g);
        let threshold = self.config.run.threshold;
        let mut tracker = SettleTracker::new(threshold);
        tracker.observe(0, zeta0.amax());
        for k in 0..self.steps {
            match observer.step(&state, &self.model, &self.y) {
                Ok(next) => state = next,
                Err(e) => {
                    let reason = match e {
                        CoreError::NoMeasurement => Divergence::MarkAtCameraPlane,
                        _ => Divergence::NonFinite,
                    };
                    return RunOutcome::Diverged { step: k, reason };
                }
            }
            tracker.observe(k + 1, (state.x - self.nominal).amax());
        }
        if !self.model.all_visible(&state.x) {
            return RunOutcome::Diverged {
                step: self.steps,
                reason: Divergence::MarkAtCameraPlane,
            };
        }
        let final_error = (state.x - self.nominal).amax();
        if final_error < threshold {
            RunOutcome::Converged {
                settle: tracker.settle_time(self.config.run.dt),
                final_error,
            }
        } else {
            RunOutcome::NotConverged { final_error }
        }
    }

    /// `phi(m)`: true iff the runs from all 64 vertices of amplitude `m`
    /// converge (stops at the first that does not).
    pub fn phi(&self, observer: &ContinuousObserver<f64, 6, 8>, v_g: f64, m: f64) -> bool {
        (0..VERTICES).all(|v| self.run(observer, v_g, &vertex(v, m)).converged())
    }

    /// Worst settling time (s) over the 64 vertices of amplitude `m`, `None`
    /// if some vertex does not converge.
    pub fn worst_settle(
        &self,
        observer: &ContinuousObserver<f64, 6, 8>,
        v_g: f64,
        m: f64,
    ) -> Option<f64> {
        let mut worst: f64 = 0.0;
        for v in 0..VERTICES {
            match self.run(observer, v_g, &vertex(v, m)) {
                RunOutcome::Converged { settle, .. } => worst = worst.max(settle),
                _ => return None,
            }
        }
        Some(worst)
    }

    /// Solves one cell: `M_zeta` and the worst settling time.
    pub fn solve(&self, cell: Cell) -> CellResult {
        let observer = self.observer(cell.alpha);
        let mz = search_m_zeta(&self.config.search, |m| self.phi(&observer, cell.v_g, m));
        let settle = self.worst_settle(&observer, cell.v_g, self.config.search.settle_m_zeta);
        CellResult {
            cell,
            m_zeta: mz.value,
            evaluations: mz.evaluations,
            settle,
        }
    }

    /// Sweeps the cells of `shard` in parallel (rayon), calling `on_cell`
    /// after each cell (from worker threads; for a progress bar).
    pub fn sweep(&self, shard: Shard, on_cell: &(dyn Fn(&CellResult) + Sync)) -> DoaResult {
        let cells: Vec<Cell> = self.cells().filter(|c| shard.contains(c.index)).collect();
        let results: Vec<CellResult> = cells
            .into_par_iter()
            .with_max_len(1)
            .map(|c| {
                let r = self.solve(c);
                on_cell(&r);
                r
            })
            .collect();
        DoaResult {
            config_hash: self.config.hash(),
            v_g_count: self.config.grid.v_g_count,
            alpha_count: self.config.grid.alpha_count,
            shard: (shard.count > 1).then_some(shard),
            cells: results,
        }
    }
}
