//! The configuration of a DOA study: the TOML schema, its defaults (the
//! spec's values), validation, and the line and column of a bad field.

use core::ops::Range;
use std::path::Path;

use locus_core::nalgebra::{SMatrix, SVector, Vector2, Vector3};
use locus_models::camera::{CameraMarks4, Intrinsics, SIGMA_E, SIGMA_PIXEL, SIGMA_T};
use serde::{Deserialize, Serialize};

use super::DoaError;

/// Largest configuration file read (bytes): a study's configuration is a
/// few hundred bytes.
pub const MAX_CONFIG_BYTES: u64 = 1 << 20;

/// Most cells of a grid (the paper's is 12 x 25 = 300): a bigger grid is
/// refused up front rather than computed for days.
pub const MAX_GRID_CELLS: usize = 100_000;

/// Most Euler steps of one run (`horizon / dt`; the spec's is 600).
pub const MAX_RUN_STEPS: f64 = 1e6;

/// Most amplitudes stepped through by the `M_zeta` search
/// (`(m_cap - m_start) / m_step`; the spec's is 39).
pub const MAX_SEARCH_STEPS: f64 = 1e4;

/// The text of the file at `path`, refused with
/// [`std::io::ErrorKind::FileTooLarge`] if longer than `max` bytes (it is
/// not read whole first).
pub(crate) fn read_bounded(path: &Path, max: u64) -> std::io::Result<String> {
    use std::io::Read;
    let mut text = String::new();
    std::fs::File::open(path)?
        .take(max + 1)
        .read_to_string(&mut text)?;
    if text.len() as u64 > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!("larger than {max} bytes, the most read"),
        ));
    }
    Ok(text)
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
    /// Reads and validates a configuration file (at most
    /// [`MAX_CONFIG_BYTES`]).
    pub fn load(path: &Path) -> Result<Self, DoaError> {
        let file = path.display().to_string();
        let text = read_bounded(path, MAX_CONFIG_BYTES).map_err(|source| DoaError::Io {
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
        for (field, count) in [
            ("grid.v_g_count", g.v_g_count),
            ("grid.alpha_count", g.alpha_count),
        ] {
            if count == 0 {
                return Err(fail(field, "must be >= 1".into()));
            }
            if count > MAX_GRID_CELLS {
                return Err(fail(
                    field,
                    format!("{count} is more than the {MAX_GRID_CELLS} cells a study may have"),
                ));
            }
        }
        if g.v_g_count * g.alpha_count > MAX_GRID_CELLS {
            return Err(fail(
                "grid.alpha_count",
                format!(
                    "a {} x {} grid is {} cells; a study may have at most {MAX_GRID_CELLS} \
                     (split it over several configurations)",
                    g.v_g_count,
                    g.alpha_count,
                    g.v_g_count * g.alpha_count
                ),
            ));
        }
        for (field, v) in [
            ("grid.v_g_start", g.v_g_start),
            ("grid.v_g_step", g.v_g_step),
            ("grid.alpha_start", g.alpha_start),
            ("grid.alpha_step", g.alpha_step),
        ] {
            if !v.is_finite() {
                return Err(fail(field, format!("must be finite, got {v}")));
            }
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
        if steps > MAX_RUN_STEPS {
            return Err(fail(
                "run.horizon",
                format!(
                    "horizon / dt is {steps:e} steps per run; at most {MAX_RUN_STEPS:e} \
                     (shorten the horizon or lengthen dt)"
                ),
            ));
        }
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
        let stepping = (s.m_cap - s.m_start) / s.m_step;
        if stepping > MAX_SEARCH_STEPS {
            return Err(fail(
                "search.m_step",
                format!(
                    "(m_cap - m_start) / m_step is {stepping:e} amplitudes to try; at most \
                     {MAX_SEARCH_STEPS:e}"
                ),
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
