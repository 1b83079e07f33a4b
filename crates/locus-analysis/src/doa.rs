//! Domain of attraction (DOA) of paper 002's continuous-time observer
//! (paper 002, section 4 and Fig. 4-5; spec `MODELS.md` section 4).
//!
//! # The study
//! The plant is at rest at the nominal pose `x_n` and the camera sees it
//! without noise: `y = h(x_n)` (eq. 5-10) at every step. The observer
//! (eq. 12-17, explicit Euler at `dt`, [`ContinuousObserver`]) starts at
//! `x^(0) = x_n + zeta0` with `P(0) = P0 = v_g Q` (eq. 23 for `Q`) and
//! weighting `alpha` (1/s). For each grid cell `(v_g, alpha)`:
//!
//! * **Run rules** (spec, \[assumed\] where the paper is silent). The error
//!   norm is the largest absolute component of `x^ - x_n` (m or rad, not
//!   wrapped: the "twin" pose with angles off by pi counts as an error). A
//!   run **diverges** as soon as a step fails: a mark at depth
//!   `z_c <= min_depth` (0.05 m, "within 0.05 m of the camera plane") or a
//!   non-finite value; it **converges** if it lasts the horizon (3 s) and the
//!   final norm is below the threshold 0.0087; otherwise it has **not
//!   converged**. There is no bound on the transient error.
//! * **phi(m)** is true iff the runs from all 64 vertices
//!   `zeta0 = m (+-1, ..., +-1)` converge ([`vertex`]).
//! * **M_zeta** (the DOA, paper's `M_zeta(P0, alpha)`): phi need not be
//!   monotone, so it is found operationally ([`search_m_zeta`]): step `m` up
//!   from 0.05 by 0.05 (cap 2.0) until the first failure, then bisect between
//!   the last success and that failure to a bracket of 0.01; `M_zeta` is the
//!   bracket's lower (successful) end.
//! * **Settling time** at a fixed `m_zeta` (0.1): over the 64 vertices, the
//!   worst time after which the norm stays below the threshold
//!   ([`SettleTracker`]); undefined (`None`) if some vertex does not converge.
//!
//! Default grid (the paper's): `v_g = 1e-4 + 5e-3 i`, `i = 0..12`, and
//! `alpha = 5 + 5 j` (1/s), `j = 0..25`.
//!
//! # Sharding
//! A sweep can be cut into `N` deterministic shards ([`Shard`]): shard `I`
//! computes the cells whose row-major index `c = i_vg n_alpha + i_alpha`
//! satisfies `c mod N = I` (interleaved, so expensive regions are spread).
//! Each cell's result depends only on the configuration and the cell, so
//! [`merge`] of all shards equals the unsharded sweep exactly; the CSV
//! ([`DoaResult::to_csv`]) writes floats in Rust's shortest round-trip form,
//! so results survive files bit for bit.

use core::fmt;
use core::ops::Range;
use std::path::Path;

use locus_core::nalgebra::{SMatrix, SVector, Vector2, Vector3};
use locus_core::{Error as CoreError, MeasurementModel};
use locus_models::camera::{CameraMarks4, Intrinsics, SIGMA_E, SIGMA_PIXEL, SIGMA_T};
use locus_models::observer::{ContinuousObserver, ObserverState};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Number of vertices of the 6-D error hypercube (`2^6`).
pub const VERTICES: usize = 64;

/// Errors of the DOA tool: each names the file and, where it has one, the
/// line and the field.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DoaError {
    /// A file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A configuration file is not valid TOML or does not fit the schema
    /// (unknown field, wrong type).
    #[error("{file}:{line}:{column}: field `{field}`: {message}")]
    Parse {
        /// The file.
        file: String,
        /// Line (1-based).
        line: usize,
        /// Column (1-based).
        column: usize,
        /// The dotted field name (`section.key`), or `?` if unknown.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A configuration value is out of its valid range.
    #[error("{file}:{line}: field `{field}`: {message}")]
    Invalid {
        /// The file (`<defaults>` for built-in values).
        file: String,
        /// Line of the field in the file (0 if the field is not in the file:
        /// a default value).
        line: usize,
        /// The dotted field name.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A `--shard I/N` specification is malformed.
    #[error("shard `{spec}`: {message}")]
    Shard {
        /// The specification as given.
        spec: String,
        /// What is wrong.
        message: String,
    },
    /// A result CSV file is malformed.
    #[error("{file}:{line}: field `{field}`: {message}")]
    Csv {
        /// The file.
        file: String,
        /// Line (1-based).
        line: usize,
        /// The column name or `header`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// Shards cannot be merged (different configurations, missing or
    /// duplicated cells).
    #[error("merge: {0}")]
    Merge(String),
}

/// The grid of the study: `v_g` (dimensionless, `P0 = v_g Q`) and `alpha`
/// (1/s), each `start + i step`, `i = 0..count`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GridConfig {
    /// First `v_g` (default 1e-4).
    pub v_g_start: f64,
    /// Step of `v_g` (default 5e-3).
    pub v_g_step: f64,
    /// Number of `v_g` values (default 12).
    pub v_g_count: usize,
    /// First `alpha` (1/s, default 5).
    pub alpha_start: f64,
    /// Step of `alpha` (1/s, default 5).
    pub alpha_step: f64,
    /// Number of `alpha` values (default 25).
    pub alpha_count: usize,
}

impl Default for GridConfig {
    fn default() -> Self {
        Self {
            v_g_start: 1e-4,
            v_g_step: 5e-3,
            v_g_count: 12,
            alpha_start: 5.0,
            alpha_step: 5.0,
            alpha_count: 25,
        }
    }
}

impl GridConfig {
    /// `v_g` of row `i`.
    pub fn v_g(&self, i: usize) -> f64 {
        self.v_g_start + self.v_g_step * i as f64
    }

    /// `alpha` (1/s) of column `j`.
    pub fn alpha(&self, j: usize) -> f64 {
        self.alpha_start + self.alpha_step * j as f64
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.v_g_count * self.alpha_count
    }
}

/// The camera and the body (paper 002, eq. 6-10), with the spec's
/// \[assumed\] marks and nominal pose as defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GeometryConfig {
    /// Four marks `X_O` in the body frame (m), eq. 6.
    pub marks: Vec<[f64; 3]>,
    /// Nominal pose `[tx, ty, tz, phi, theta, psi]` (m, rad), eq. 2.
    pub nominal_pose: [f64; 6],
    /// Focal lengths `(l_x, l_y)` (px), eq. 10.
    pub focal: [f64; 2],
    /// Principal point `(o_x, o_y)` (px), eq. 10.
    pub principal: [f64; 2],
    /// Radial distortion `Kc1` (-), eq. 9.
    pub kc1: f64,
    /// Divergence depth: a run diverges when a mark has `z_c <=` this (m).
    pub min_depth: f64,
}

impl Default for GeometryConfig {
    fn default() -> Self {
        Self {
            marks: vec![
                [0.30, 0.0, 0.0],
                [-0.30, 0.0, 0.0],
                [0.0, 0.20, 0.0],
                [0.0, -0.10, 0.15],
            ],
            nominal_pose: [0.0, 0.0, 2.5, 0.0, 0.0, 0.0],
            focal: [1865.33, 1868.57],
            principal: [510.68, 619.68],
            kc1: -0.19457,
            min_depth: 0.05,
        }
    }
}

/// Noise densities of the observer (paper 002, eq. 23).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NoiseConfig {
    /// Diagonal of `Q` (m^2/s x3, rad^2/s x3; default `0.1^2 x3, 0.1396^2 x3`).
    pub q_diag: [f64; 6],
    /// Pixel standard deviation `sigma_p` (px): `Theta = sigma_p^2 I_8`.
    pub pixel_sigma: f64,
}

impl Default for NoiseConfig {
    fn default() -> Self {
        let (t, e) = (SIGMA_T * SIGMA_T, SIGMA_E * SIGMA_E);
        Self {
            q_diag: [t, t, t, e, e, e],
            pixel_sigma: SIGMA_PIXEL,
        }
    }
}

/// One run of the observer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RunConfig {
    /// Euler step (s, default 0.005).
    pub dt: f64,
    /// Length of a run (s, default 3; a whole number of steps).
    pub horizon: f64,
    /// Convergence threshold on the error norm (m or rad, default 0.0087).
    pub threshold: f64,
}

impl Default for RunConfig {
    fn default() -> Self {
        Self {
            dt: 0.005,
            horizon: 3.0,
            threshold: 0.0087,
        }
    }
}

impl RunConfig {
    /// Number of Euler steps of a run: `round(horizon / dt)`.
    pub fn steps(&self) -> usize {
        (self.horizon / self.dt).round() as usize
    }
}

/// The search for `M_zeta` (stepping, then bisection) and the settling-time
/// amplitude.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SearchConfig {
    /// First amplitude tried (m, rad; default 0.05).
    pub m_start: f64,
    /// Stepping increment (default 0.05).
    pub m_step: f64,
    /// Largest amplitude tried (default 2.0).
    pub m_cap: f64,
    /// Bisection stops when the bracket is at most this wide (default 0.01).
    pub tolerance: f64,
    /// Amplitude at which the settling time is measured (default 0.1).
    pub settle_m_zeta: f64,
}

impl Default for SearchConfig {
    fn default() -> Self {
        Self {
            m_start: 0.05,
            m_step: 0.05,
            m_cap: 2.0,
            tolerance: 0.01,
            settle_m_zeta: 0.1,
        }
    }
}

/// The whole configuration of a DOA study, as read from TOML (every field
/// optional; defaults are the spec's values).
///
/// ```toml
/// [grid]
/// v_g_count = 4
/// alpha_start = 25.0
/// [run]
/// horizon = 2.0
/// ```
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DoaConfig {
    /// The `(v_g, alpha)` grid.
    pub grid: GridConfig,
    /// Camera and marks.
    pub geometry: GeometryConfig,
    /// Noise densities.
    pub noise: NoiseConfig,
    /// One run.
    pub run: RunConfig,
    /// The `M_zeta` search and the settling amplitude.
    pub search: SearchConfig,
}

impl DoaConfig {
    /// Reads and validates a configuration file.
    pub fn load(path: &Path) -> Result<Self, DoaError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| DoaError::Io {
            file: file.clone(),
            source,
        })?;
        Self::from_toml_str(&text, &file)
    }

    /// Parses and validates a configuration from TOML text; `file` names it
    /// in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, DoaError> {
        let config: Self = toml::from_str(text).map_err(|e| {
            let span = e.span().unwrap_or(0..0);
            let (line, column) = line_col(text, span.start);
            DoaError::Parse {
                file: file.to_owned(),
                line,
                column,
                field: field_at(text, &span, e.message()),
                message: e.message().to_owned(),
            }
        })?;
        config.validate_in(text, file)?;
        Ok(config)
    }

    /// Validates the built-in or programmatic configuration (errors name
    /// `<defaults>` as the file).
    pub fn validate(&self) -> Result<(), DoaError> {
        self.validate_in("", "<defaults>")
    }

    fn validate_in(&self, text: &str, file: &str) -> Result<(), DoaError> {
        let fail = |field: &str, message: String| DoaError::Invalid {
            file: file.to_owned(),
            line: find_field_line(text, field),
            field: field.to_owned(),
            message,
        };
        let finite_pos = |field: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(fail(field, format!("must be finite and > 0, got {v}")))
            }
        };
        let g = &self.grid;
        if g.v_g_count == 0 {
            return Err(fail("grid.v_g_count", "must be >= 1".into()));
        }
        if g.alpha_count == 0 {
            return Err(fail("grid.alpha_count", "must be >= 1".into()));
        }
        if !(g.v_g_step.is_finite() && g.v_g_start.is_finite()) {
            return Err(fail("grid.v_g_step", "must be finite".into()));
        }
        if !(g.alpha_step.is_finite() && g.alpha_start.is_finite()) {
            return Err(fail("grid.alpha_step", "must be finite".into()));
        }
        for i in [0, g.v_g_count - 1] {
            let v = g.v_g(i);
            if v <= 0.0 {
                return Err(fail("grid.v_g_start", format!("v_g must be > 0, got {v}")));
            }
        }
        for j in [0, g.alpha_count - 1] {
            let a = g.alpha(j);
            if a < 0.0 {
                return Err(fail(
                    "grid.alpha_start",
                    format!("alpha must be >= 0, got {a}"),
                ));
            }
        }
        let geo = &self.geometry;
        if geo.marks.len() != 4 {
            return Err(fail(
                "geometry.marks",
                format!("exactly 4 marks are needed, got {}", geo.marks.len()),
            ));
        }
        if !geo.marks.iter().flatten().all(|v| v.is_finite())
            || !geo.nominal_pose.iter().all(|v| v.is_finite())
        {
            return Err(fail("geometry.marks", "must be finite".into()));
        }
        finite_pos("geometry.focal", geo.focal[0].min(geo.focal[1]))?;
        if !(geo.principal.iter().all(|v| v.is_finite()) && geo.kc1.is_finite()) {
            return Err(fail("geometry.kc1", "must be finite".into()));
        }
        finite_pos("geometry.min_depth", geo.min_depth)?;
        let model = self.model();
        if !model.all_visible(&self.nominal()) {
            return Err(fail(
                "geometry.nominal_pose",
                "every mark must be deeper than min_depth at the nominal pose".into(),
            ));
        }
        if !self.noise.q_diag.iter().all(|v| v.is_finite() && *v >= 0.0) {
            return Err(fail("noise.q_diag", "must be finite and >= 0".into()));
        }
        finite_pos("noise.pixel_sigma", self.noise.pixel_sigma)?;
        let r = &self.run;
        finite_pos("run.dt", r.dt)?;
        finite_pos("run.horizon", r.horizon)?;
        finite_pos("run.threshold", r.threshold)?;
        let steps = r.horizon / r.dt;
        if (steps - steps.round()).abs() > 1e-9 * steps.max(1.0) || steps.round() < 1.0 {
            return Err(fail(
                "run.horizon",
                format!("must be a whole number (>= 1) of steps dt, got {steps} steps"),
            ));
        }
        let s = &self.search;
        finite_pos("search.m_start", s.m_start)?;
        finite_pos("search.m_step", s.m_step)?;
        finite_pos("search.tolerance", s.tolerance)?;
        finite_pos("search.settle_m_zeta", s.settle_m_zeta)?;
        if !(s.m_cap.is_finite() && s.m_cap >= s.m_start) {
            return Err(fail(
                "search.m_cap",
                format!("must be finite and >= m_start, got {}", s.m_cap),
            ));
        }
        Ok(())
    }

    /// The camera model of the configuration.
    pub fn model(&self) -> CameraMarks4<f64> {
        let geo = &self.geometry;
        let mark = |i: usize| Vector3::from(geo.marks[i]);
        CameraMarks4::new(
            Intrinsics {
                focal: Vector2::from(geo.focal),
                principal: Vector2::from(geo.principal),
                kc1: geo.kc1,
            },
            [mark(0), mark(1), mark(2), mark(3)],
        )
        .with_min_depth(geo.min_depth)
        .with_pixel_var(self.noise.pixel_sigma * self.noise.pixel_sigma)
    }

    /// The nominal pose `x_n` (m, rad).
    pub fn nominal(&self) -> SVector<f64, 6> {
        SVector::from(self.geometry.nominal_pose)
    }

    /// The process-noise density `Q = diag(q_diag)` (m^2/s, rad^2/s).
    pub fn noise_q(&self) -> SMatrix<f64, 6, 6> {
        SMatrix::from_diagonal(&SVector::from(self.noise.q_diag))
    }

    /// A 64-bit FNV-1a hash of the configuration's canonical TOML form: shards
    /// of one study carry the same hash.
    pub fn hash(&self) -> u64 {
        let text = toml::to_string(self).unwrap_or_default();
        text.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
        })
    }
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |p| p + 1) + 1;
    (line, column)
}

/// The dotted name of the field at `span`: the key of that line (text before
/// `=`) under the last `[section]` header above it, or the field named in
/// the message (`unknown field `x``).
fn field_at(text: &str, span: &Range<usize>, message: &str) -> String {
    let start = span.start.min(text.len());
    let line_start = text[..start].rfind('\n').map_or(0, |p| p + 1);
    let line_end = text[start..].find('\n').map_or(text.len(), |p| start + p);
    let line = &text[line_start..line_end];
    let section = text[..line_start]
        .lines()
        .rev()
        .find_map(|l| {
            let l = l.trim();
            (l.starts_with('[') && l.ends_with(']'))
                .then(|| l.trim_matches(|c| c == '[' || c == ']').trim().to_owned())
        })
        .unwrap_or_default();
    let key = if let Some((k, _)) = line.split_once('=') {
        k.trim().to_owned()
    } else if let Some(rest) = message.split_once("unknown field `") {
        rest.1.split('`').next().unwrap_or("?").to_owned()
    } else {
        let l = line.trim();
        if l.starts_with('[') {
            return l.trim_matches(|c| c == '[' || c == ']').trim().to_owned();
        }
        "?".to_owned()
    };
    if section.is_empty() {
        key
    } else {
        format!("{section}.{key}")
    }
}

/// Line (1-based) where `section.key` is set in `text`, 0 if absent.
fn find_field_line(text: &str, field: &str) -> usize {
    let (section, key) = field.split_once('.').unwrap_or(("", field));
    let mut current = String::new();
    for (i, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.starts_with('[') && t.ends_with(']') {
            current = t.trim_matches(|c| c == '[' || c == ']').trim().to_owned();
        } else if let Some((k, _)) = t.split_once('=') {
            if current == section && k.trim() == key {
                return i + 1;
            }
        }
    }
    0
}

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

/// The outcome of one run (see the module's run rules).
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

/// A deterministic slice `index / count` of a sweep (0-based index).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard (0-based, `< count`).
    pub index: usize,
    /// Number of shards (>= 1).
    pub count: usize,
}

impl Shard {
    /// The whole sweep (`0/1`).
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N` (0-based `I < N`).
    pub fn parse(spec: &str) -> Result<Self, DoaError> {
        let bad = |message: &str| DoaError::Shard {
            spec: spec.to_owned(),
            message: message.to_owned(),
        };
        let (i, n) = spec
            .split_once('/')
            .ok_or_else(|| bad("expected I/N, e.g. 0/8"))?;
        let index: usize = i
            .trim()
            .parse()
            .map_err(|_| bad("I is not a whole number"))?;
        let count: usize = n
            .trim()
            .parse()
            .map_err(|_| bad("N is not a whole number"))?;
        if count == 0 {
            return Err(bad("N must be >= 1"));
        }
        if index >= count {
            return Err(bad("I must be < N (0-based)"));
        }
        Ok(Self { index, count })
    }

    /// True if cell `index` belongs to this shard.
    pub fn contains(&self, cell_index: usize) -> bool {
        cell_index % self.count == self.index
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
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

/// The results of a sweep or a shard of it.
#[derive(Debug, Clone, PartialEq)]
pub struct DoaResult {
    /// [`DoaConfig::hash`] of the study.
    pub config_hash: u64,
    /// Rows of the grid.
    pub v_g_count: usize,
    /// Columns of the grid.
    pub alpha_count: usize,
    /// The shard these results are (`None`: the whole grid).
    pub shard: Option<Shard>,
    /// The cells, by increasing index.
    pub cells: Vec<CellResult>,
}

const CSV_MAGIC: &str = "# locus-doa v1";
const CSV_HEADER: &str = "index,i_vg,i_alpha,v_g,alpha,m_zeta,evaluations,settle_time_s";

impl DoaResult {
    /// The CSV form: a comment line with the configuration hash, grid and
    /// shard, the header, then one line per cell (floats in shortest
    /// round-trip form; an empty settling time means some vertex did not
    /// converge).
    pub fn to_csv(&self) -> String {
        let shard = self.shard.map_or("all".to_owned(), |s| s.to_string());
        let mut out = format!(
            "{CSV_MAGIC} config={:016x} grid={}x{} shard={shard}\n{CSV_HEADER}\n",
            self.config_hash, self.v_g_count, self.alpha_count
        );
        for r in &self.cells {
            let c = &r.cell;
            let settle = r.settle.map_or(String::new(), |s| s.to_string());
            out.push_str(&format!(
                "{},{},{},{},{},{},{},{}\n",
                c.index, c.i_vg, c.i_alpha, c.v_g, c.alpha, r.m_zeta, r.evaluations, settle
            ));
        }
        out
    }

    /// Parses [`to_csv`](Self::to_csv)'s form; `file` names it in errors.
    pub fn from_csv(text: &str, file: &str) -> Result<Self, DoaError> {
        let err = |line: usize, field: &str, message: String| DoaError::Csv {
            file: file.to_owned(),
            line,
            field: field.to_owned(),
            message,
        };
        let mut lines = text.lines().enumerate();
        let (_, first) = lines
            .next()
            .ok_or_else(|| err(1, "header", "empty file".into()))?;
        let rest = first.strip_prefix(CSV_MAGIC).ok_or_else(|| {
            err(
                1,
                "header",
                format!("expected `{CSV_MAGIC} ...`, got `{first}`"),
            )
        })?;
        let (mut hash, mut grid, mut shard) = (None, None, None);
        for kv in rest.split_whitespace() {
            match kv.split_once('=') {
                Some(("config", v)) => hash = u64::from_str_radix(v, 16).ok(),
                Some(("grid", v)) => {
                    grid = v
                        .split_once('x')
                        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
                }
                Some(("shard", "all")) => shard = Some(None),
                Some(("shard", v)) => shard = Shard::parse(v).ok().map(Some),
                _ => {}
            }
        }
        let config_hash = hash.ok_or_else(|| err(1, "config", "missing or malformed".into()))?;
        let (v_g_count, alpha_count) =
            grid.ok_or_else(|| err(1, "grid", "missing or malformed".into()))?;
        let shard = shard.ok_or_else(|| err(1, "shard", "missing or malformed".into()))?;
        match lines.next() {
            Some((_, h)) if h == CSV_HEADER => {}
            _ => return Err(err(2, "header", format!("expected `{CSV_HEADER}`"))),
        }
        let names: Vec<&str> = CSV_HEADER.split(',').collect();
        let mut cells = Vec::new();
        for (i, line) in lines {
            let n = i + 1;
            if line.trim().is_empty() {
                continue;
            }
            let f: Vec<&str> = line.split(',').collect();
            if f.len() != names.len() {
                return Err(err(
                    n,
                    "line",
                    format!("expected {} fields, got {}", names.len(), f.len()),
                ));
            }
            let int = |k: usize| {
                f[k].parse::<usize>()
                    .map_err(|e| err(n, names[k], format!("`{}`: {e}", f[k])))
            };
            let float = |k: usize| {
                f[k].parse::<f64>()
                    .map_err(|e| err(n, names[k], format!("`{}`: {e}", f[k])))
            };
            let evaluations = f[6]
                .parse::<u32>()
                .map_err(|e| err(n, names[6], format!("`{}`: {e}", f[6])))?;
            let settle = if f[7].is_empty() {
                None
            } else {
                Some(float(7)?)
            };
            cells.push(CellResult {
                cell: Cell {
                    index: int(0)?,
                    i_vg: int(1)?,
                    i_alpha: int(2)?,
                    v_g: float(3)?,
                    alpha: float(4)?,
                },
                m_zeta: float(5)?,
                evaluations,
                settle,
            });
        }
        Ok(Self {
            config_hash,
            v_g_count,
            alpha_count,
            shard,
            cells,
        })
    }

    /// The cell at `(i_vg, i_alpha)`, if present.
    pub fn get(&self, i_vg: usize, i_alpha: usize) -> Option<&CellResult> {
        self.cells
            .iter()
            .find(|r| r.cell.i_vg == i_vg && r.cell.i_alpha == i_alpha)
    }
}

/// Joins shards into the whole grid: every part must have the same
/// configuration hash and grid, and together they must hold every cell
/// exactly once. The result equals the unsharded sweep.
pub fn merge(parts: Vec<DoaResult>) -> Result<DoaResult, DoaError> {
    let first = parts
        .first()
        .ok_or_else(|| DoaError::Merge("no shards given".into()))?;
    let (hash, nv, na) = (first.config_hash, first.v_g_count, first.alpha_count);
    let total = nv * na;
    let mut slots: Vec<Option<CellResult>> = vec![None; total];
    for (k, part) in parts.iter().enumerate() {
        if part.config_hash != hash {
            return Err(DoaError::Merge(format!(
                "shard {k} has configuration {:016x}, shard 0 has {hash:016x}",
                part.config_hash
            )));
        }
        if (part.v_g_count, part.alpha_count) != (nv, na) {
            return Err(DoaError::Merge(format!(
                "shard {k} has a {}x{} grid, shard 0 has {nv}x{na}",
                part.v_g_count, part.alpha_count
            )));
        }
        for r in &part.cells {
            let i = r.cell.index;
            if i >= total || r.cell.i_vg * na + r.cell.i_alpha != i {
                return Err(DoaError::Merge(format!(
                    "shard {k}: cell index {i} does not fit the grid"
                )));
            }
            if slots[i].replace(*r).is_some() {
                return Err(DoaError::Merge(format!("cell {i} appears twice")));
            }
        }
    }
    let missing: Vec<usize> = (0..total).filter(|&i| slots[i].is_none()).collect();
    if !missing.is_empty() {
        return Err(DoaError::Merge(format!(
            "{} cells missing (first: {:?})",
            missing.len(),
            &missing[..missing.len().min(5)]
        )));
    }
    Ok(DoaResult {
        config_hash: hash,
        v_g_count: nv,
        alpha_count: na,
        shard: None,
        cells: slots.into_iter().flatten().collect(),
    })
}
