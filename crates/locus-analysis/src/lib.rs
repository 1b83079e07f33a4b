//! Analysis tools of Locus, built on the papers' models.
//!
//! * [`doa`]: the domain of attraction of paper 002's continuous-time
//!   observer (spec `MODELS.md` section 4): for each cell `(v_g, alpha)` of a
//!   grid, the largest initial error `M_zeta` from which the observer still
//!   converges from all 64 vertices of the error hypercube, and the worst
//!   settling time at a fixed initial error. Configured from TOML, parallel
//!   over cells (rayon), sliced into deterministic shards that merge back
//!   exactly.
//! * [`hw`]: a cycle-level model of the FPGA correction core of papers 000
//!   and 003 (a state machine with states waiting, mult1, mult2, multadd,
//!   add, div1 running the 11-step schedule of spec section 1), with
//!   configurable operator latencies, number of parallel datapaths and clock.
//!   It executes the arithmetic in `f32` in the schedule's order and counts
//!   the floating-point operators the schedule needs.
//! * [`hdl`]: Verilog binary32 adder, multiplier and divider for that core
//!   (repository directory `hdl/`), bit-exact against Rust's `f32`, with
//!   the vector generator and the Icarus Verilog runner that test them.
//!
//! Units are SI inside (m, rad, s); the paper's pixels are px.

pub mod doa;
pub mod hdl;
pub mod hw;
