//! Domain of attraction (DOA) of paper 002's continuous-time observer
//! (paper 002, section 4 and Fig. 4-5; spec `MODELS.md` section 4).
//!
//! # The study
//! The plant is at rest at the nominal pose `x_n` and the camera sees it
//! without noise: `y = h(x_n)` (eq. 5-10) at every step. The observer
//! (eq. 12-17, explicit Euler at `dt`,
//! [`ContinuousObserver`](locus_models::observer::ContinuousObserver))
//! starts at `x^(0) = x_n + zeta0` with `P(0) = P0 = v_g Q` (eq. 23 for
//! `Q`) and weighting `alpha` (1/s). For each grid cell `(v_g, alpha)`:
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

mod config;
mod shards;
mod study;

pub use config::{
    DoaConfig, GeometryConfig, GridConfig, MAX_CONFIG_BYTES, MAX_GRID_CELLS, MAX_RUN_STEPS,
    MAX_SEARCH_STEPS, NoiseConfig, RunConfig, SearchConfig,
};
pub use shards::{DoaResult, Shard, merge, merge_csv};
pub use study::{
    Cell, CellResult, Divergence, MZeta, RunOutcome, SettleTracker, Study, VERTICES, search_m_zeta,
    vertex,
};

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
    #[error("{file}{at}: field `{field}`: {message}",
        at = if *.line == 0 { " (value not set in the file)".to_owned() } else { format!(":{line}") })]
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
