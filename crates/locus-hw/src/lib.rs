//! Cycle-level model of the EKF correction core of papers 000 and 003
//! (spec `MODELS.md` section 1; paper 000 section III.B, Fig. 3-4 and
//! eq. 16-26; paper 003 eq. 3-13, Fig. 3-5 and Table 1).
//!
//! # The machine
//! A finite state machine with the states of the papers' Fig. 3 —
//! [`State::Waiting`], [`State::Mult1`], [`State::Mult2`],
//! [`State::Multadd`], [`State::Add`], [`State::Div1`] — drives `D`
//! identical datapaths (paper 003: nine, one per element of the largest,
//! 3x3, result). Each datapath has one pipelined floating-point multiplier
//! and one adder/subtractor; the first `min(D, dividers)` datapaths also
//! have a divider (paper 003: datapaths 1-4, for the four entries of the
//! 2x2 inverse). A step of the schedule computes the elements of its result
//! matrix, `D` at a time (waves); every element of a step has the same
//! shape, so a wave takes the same number of cycles.
//!
//! This model's reading of the states (the papers name them but do not
//! define them cycle by cycle):
//! * `mult1`: the first product of an element enters the multiplier; its
//!   result is ready after the multiplier latency `L_mul`.
//! * `mult2`: the second product enters one cycle later (pipelined); 1 cycle
//!   (none when the core forwards it, [`HwConfig::forward`]).
//! * `multadd`: the adder accumulates the products, `((p1 + p2) + p3)`, one
//!   addition of latency `L_add` after another (the later products are
//!   ready by then).
//! * `add`: an element-wise sum or difference, `L_add`.
//! * `div1`: element-wise divisions on the dividers only, which are
//!   pipelined: `L_div` for as many divisions as dividers, one cycle more
//!   for each further division a divider takes.
//! * `waiting`: idle until `start`; one cycle to leave it.
//!
//! So a dot product of length `k` takes `L_mul` (k = 1) or
//! `L_mul + 1 + (k - 1) L_add` cycles; every state visit adds
//! `transition` cycles (the state register and the write into the
//! intermediate bank). Steps run one after another, as in the papers' FSM
//! (no overlap of independent steps; the Verilog core runs steps 6-8 on
//! operators other steps leave idle, [`HwConfig::overlap`]).
//!
//! # Schedules
//! * [`Schedule::Inverse2x2`]: the papers' 11 steps (spec section 1, n = 3,
//!   m = 2): `O1 = P- H^T`, `O2 = H O1`, `O3 = O2 + R`, `O4 = inv(O3)`
//!   (determinant `a d - b c` on one datapath, then four divisions),
//!   `G = O1 O4`, `O5 = z - h(X-)`, `O6 = G O5`, `X+ = X- + O6`,
//!   `O7 = G H`, `O8 = O7 P-`, `P+ = P- - O8`: the plain covariance update.
//! * [`Schedule::Scalar`]: the measurement components one at a time (R
//!   diagonal), each with one division per gain entry and no inverse; `h`
//!   and `H` stay those of the prior, and component `i` sees the innovation
//!   `z_i - h_i(X-) - H_i (X - X-)`, so the result equals the batch update in
//!   exact arithmetic (as `locus_core::Ekf::correct_sequential`).
//!
//! The arithmetic is executed in `f32` in the schedule's order (products
//! accumulated left to right), so the result is what the core would output.
//!
//! # The Verilog
//! [`hdl`]: the core's binary32 adder, multiplier and divider and the core
//! itself in Verilog (repository directory `hdl/`), bit-exact against
//! Rust's `f32` and against [`run`], with the vector generators and the
//! Icarus Verilog runners that test them.

use core::fmt;

pub mod hdl;

use locus_core::nalgebra::{Matrix2, Matrix2x3, Matrix3, Matrix3x2, SMatrix, Vector2, Vector3};

/// A state of the correction FSM (papers 000/003, Fig. 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum State {
    /// Idle until `start`.
    Waiting,
    /// First product of an element (multiplier latency).
    Mult1,
    /// Second product, pipelined behind the first (1 cycle).
    Mult2,
    /// Accumulation of the products by the adder.
    Multadd,
    /// Element-wise addition or subtraction.
    Add,
    /// Element-wise division (dividers only).
    Div1,
}

impl State {
    /// The papers' name of the state.
    pub fn name(self) -> &'static str {
        match self {
            Self::Waiting => "waiting",
            Self::Mult1 => "mult1",
            Self::Mult2 => "mult2",
            Self::Multadd => "multadd",
            Self::Add => "add",
            Self::Div1 => "div1",
        }
    }
}

impl fmt::Display for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Latencies of the floating-point operators and of a state change (clock
/// cycles).
///
/// The defaults are the fastest single-precision configurations of Intel's
/// (Altera's) floating-point IP cores for Cyclone IV (Floating-Point IP
/// Cores User Guide, ID 683750: ALTFP_MULT 5 cycles, ALTFP_ADD_SUB 7,
/// ALTFP_DIV 6); see `docs/hw.md` for the ranges and sources. They are not
/// fitted to the papers' measured time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Latencies {
    /// Multiplier latency (cycles, >= 1).
    pub mul: u64,
    /// Adder/subtractor latency (cycles, >= 1).
    pub add: u64,
    /// Divider latency (cycles, >= 1).
    pub div: u64,
    /// Cycles added by every state visit (state register, bank write; >= 0).
    pub transition: u64,
}

impl Default for Latencies {
    fn default() -> Self {
        Self::ALTFP_FASTEST
    }
}

impl Latencies {
    /// Fastest single-precision ALTFP configurations: mult 5, add/sub 7,
    /// div 6, one cycle per state change.
    pub const ALTFP_FASTEST: Self = Self {
        mul: 5,
        add: 7,
        div: 6,
        transition: 1,
    };
    /// Slowest (highest-Fmax) single-precision ALTFP configurations: mult 11,
    /// add/sub 14, div 33, one cycle per state change.
    pub const ALTFP_SLOWEST: Self = Self {
        mul: 11,
        add: 14,
        div: 33,
        transition: 1,
    };
}

/// Configuration of the modelled core.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HwConfig {
    /// Operator latencies.
    pub latencies: Latencies,
    /// Number of parallel datapaths `D` (>= 1; the papers' core has 9).
    pub datapaths: usize,
    /// Number of datapaths that carry a divider (>= 1; the papers' core has
    /// 4); the core has `min(datapaths, dividers)` dividers.
    pub dividers: usize,
    /// Clock frequency (Hz, > 0; the papers' timings are at 50 MHz).
    pub clock_hz: f64,
    /// The second product of a dot product enters the adder in the cycle it
    /// leaves the multiplier, so `mult2` takes no cycle of its own (the
    /// Verilog core; the papers' FSM has the state, `false`).
    pub forward: bool,
    /// Steps run on operators other steps' waves leave idle (the Verilog
    /// core; `false` in the papers' strictly sequential FSM). Steps 6-8
    /// have no wave of their own: `O5 = z - h(X-)` on two adders before
    /// step 1's first sum; `O6 = G O5` inside step 9's wave (three
    /// multipliers take its products after O7's, its sums leave the adders
    /// two cycles after O7's: that wave's `multadd` is two cycles longer);
    /// `X+ = X- + O6` on three adders before step 10's first sum. With 6 to
    /// 8 datapaths a 3x3 step (9, 10, 11) is still one wave: its row 2
    /// (group 2) runs on datapaths 3-5, in step 9 beside O6 (no cost), in
    /// step 10 from cycle `L_add + 1` on (its first sum one cycle after
    /// group 1's last: `multadd` `L_add + 1` cycles longer), in step 11 one
    /// cycle after group 1 (`add` one cycle longer). It needs at least six
    /// datapaths: with fewer, every step keeps its waves.
    pub overlap: bool,
    /// Element-wise sums and differences take one cycle more: their
    /// operands pass a register before the adder (the Verilog core, whose
    /// adder has no operand register of its own; `false` in the papers'
    /// reading, where the operator's latency covers it).
    pub elementwise_register: bool,
}

impl Default for HwConfig {
    /// The papers' core: 9 datapaths, 4 dividers, 50 MHz, fastest ALTFP
    /// latencies.
    fn default() -> Self {
        Self {
            latencies: Latencies::default(),
            datapaths: 9,
            dividers: 4,
            clock_hz: 50e6,
            forward: false,
            overlap: false,
            elementwise_register: false,
        }
    }
}

/// Errors of the hardware model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum HwError {
    /// A configuration value is out of range.
    #[error("hw configuration: `{field}` {message}")]
    InvalidConfig {
        /// The field.
        field: &'static str,
        /// What is wrong.
        message: &'static str,
    },
    /// The innovation covariance cannot be inverted (zero determinant or
    /// non-positive scalar variance) or a result is not finite.
    #[error("hw correction: {0}")]
    Numeric(&'static str),
}

impl HwConfig {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), HwError> {
        let bad = |field, message| Err(HwError::InvalidConfig { field, message });
        if self.datapaths == 0 {
            return bad("datapaths", "must be >= 1");
        }
        if self.dividers == 0 {
            return bad("dividers", "must be >= 1");
        }
        let l = &self.latencies;
        if l.mul == 0 || l.add == 0 || l.div == 0 {
            return bad("latencies", "must be >= 1 cycle each");
        }
        if !(self.clock_hz.is_finite() && self.clock_hz > 0.0) {
            return bad("clock_hz", "must be finite and > 0");
        }
        Ok(())
    }
}

/// Which correction the core runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Schedule {
    /// The papers' 11 steps with the 2x2 inverse.
    Inverse2x2,
    /// Scalar updates, one measurement component at a time (R diagonal).
    Scalar,
}

/// The input bank of the core (papers 000/003: written by the Nios II, which
/// computes `H` and `h(X-)` in software): n = 3 states, m = 2 measurements.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoreInputs {
    /// Prior state `X-`.
    pub x: Vector3<f32>,
    /// Prior covariance `P-` (symmetric).
    pub p: Matrix3<f32>,
    /// Measurement Jacobian `H` (2 x 3).
    pub h: Matrix2x3<f32>,
    /// Measurement noise `R` (2 x 2; diagonal for [`Schedule::Scalar`]).
    pub r: Matrix2<f32>,
    /// Measurement `z`.
    pub z: Vector2<f32>,
    /// Predicted measurement `h(X-)`.
    pub hx: Vector2<f32>,
}

/// Operator counts (multipliers, adders/subtractors, dividers).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OpCounts {
    /// Multiplications (or multipliers).
    pub mul: usize,
    /// Additions/subtractions (or adders).
    pub add: usize,
    /// Divisions (or dividers).
    pub div: usize,
}

/// One state visit of one wave of one step, as the FSM runs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phase {
    /// The step's label (`"1 O1 = P- H^T"`, ...).
    pub step: &'static str,
    /// The state.
    pub state: State,
    /// First cycle.
    pub start: u64,
    /// Cycles spent (latency plus the transition).
    pub cycles: u64,
    /// Datapaths busy.
    pub active: usize,
}

/// The result of one modelled correction.
#[derive(Debug, Clone, PartialEq)]
pub struct CoreRun {
    /// Posterior state `X+` (f32, as the core computes it).
    pub x_post: Vector3<f32>,
    /// Posterior covariance `P+` (plain form).
    pub p_post: Matrix3<f32>,
    /// The gain `G` (step 5); for scalar updates, the gain of component
    /// `i` in column `i`.
    pub gain: Matrix3x2<f32>,
    /// Total clock cycles from `start` to done.
    pub cycles: u64,
    /// Time per correction (s): `cycles / clock_hz`.
    pub time_s: f64,
    /// Operators needed: the largest number of each kind busy at once.
    pub operators: OpCounts,
    /// Operations executed.
    pub operations: OpCounts,
    /// Every state visit in order.
    pub trace: Vec<Phase>,
}

impl CoreRun {
    /// Cycles spent in each state, in the order of [`State`].
    pub fn cycles_per_state(&self) -> [(State, u64); 6] {
        let states = [
            State::Waiting,
            State::Mult1,
            State::Mult2,
            State::Multadd,
            State::Add,
            State::Div1,
        ];
        states.map(|s| {
            (
                s,
                self.trace
                    .iter()
                    .filter(|p| p.state == s)
                    .map(|p| p.cycles)
                    .sum(),
            )
        })
    }
}

struct Machine {
    cfg: HwConfig,
    /// Charge a step's elements as one wave, whatever the datapaths
    /// ([`HwConfig::overlap`] with 6-8 datapaths).
    one_wave: bool,
    cycle: u64,
    trace: Vec<Phase>,
    peak: OpCounts,
    done: OpCounts,
}

impl Machine {
    fn new(cfg: HwConfig) -> Self {
        let mut m = Self {
            cfg,
            one_wave: false,
            cycle: 0,
            trace: Vec::new(),
            peak: OpCounts::default(),
            done: OpCounts::default(),
        };
        m.visit("start", State::Waiting, 1, 0);
        m
    }

    fn visit(&mut self, step: &'static str, state: State, latency: u64, active: usize) {
        let cycles = latency + self.cfg.latencies.transition;
        self.trace.push(Phase {
            step,
            state,
            start: self.cycle,
            cycles,
            active,
        });
        self.cycle += cycles;
    }

    /// Charges `elements` identical element computations: in waves of
    /// `lanes`, each wave visiting `states`; `ops` per element.
    fn charge(
        &mut self,
        step: &'static str,
        elements: usize,
        states: &[(State, u64)],
        ops: OpCounts,
    ) {
        let lanes = if self.one_wave {
            elements
        } else {
            self.cfg.datapaths
        };
        let mut left = elements;
        while left > 0 {
            let issued = left.min(lanes);
            let busy = issued.min(self.cfg.datapaths);
            for &(state, latency) in states {
                self.visit(step, state, latency, busy);
            }
            if ops.mul > 0 {
                self.peak.mul = self.peak.mul.max(busy);
            }
            if ops.add > 0 {
                self.peak.add = self.peak.add.max(busy);
            }
            if ops.div > 0 {
                self.peak.div = self.peak.div.max(busy);
            }
            left -= issued;
        }
        self.done.mul += ops.mul * elements;
        self.done.add += ops.add * elements;
        self.done.div += ops.div * elements;
    }

    /// `a b` with each element `((a0 b0 + a1 b1) + a2 b2)` in f32.
    fn matmul<const R: usize, const K: usize, const C: usize>(
        &mut self,
        step: &'static str,
        a: &SMatrix<f32, R, K>,
        b: &SMatrix<f32, K, C>,
    ) -> SMatrix<f32, R, C> {
        let out = product(a, b);
        let l = self.cfg.latencies;
        let multadd = (K as u64 - 1) * l.add;
        let states: &[(State, u64)] = if K == 1 {
            &[(State::Mult1, l.mul)]
        } else if self.cfg.forward {
            &[(State::Mult1, l.mul), (State::Multadd, multadd)]
        } else {
            &[
                (State::Mult1, l.mul),
                (State::Mult2, 1),
                (State::Multadd, multadd),
            ]
        };
        self.charge(
            step,
            R * C,
            states,
            OpCounts {
                mul: K,
                add: K - 1,
                div: 0,
            },
        );
        out
    }

    /// `a + b` (or `a - b`) element-wise in f32.
    fn addsub<const R: usize, const C: usize>(
        &mut self,
        step: &'static str,
        a: &SMatrix<f32, R, C>,
        b: &SMatrix<f32, R, C>,
        subtract: bool,
    ) -> SMatrix<f32, R, C> {
        let out = if subtract { a - b } else { a + b };
        let l = self.cfg.latencies;
        let latency = l.add + u64::from(self.cfg.elementwise_register);
        self.charge(
            step,
            R * C,
            &[(State::Add, latency)],
            OpCounts {
                mul: 0,
                add: 1,
                div: 0,
            },
        );
        out
    }

    /// Counts `ops` executed on operators another step's wave leaves idle
    /// ([`HwConfig::overlap`]): no cycles of their own.
    fn beside(&mut self, ops: OpCounts) {
        self.done.mul += ops.mul;
        self.done.add += ops.add;
        self.done.div += ops.div;
    }

    /// Lengthens the last state visit by `cycles`.
    fn extend_last(&mut self, cycles: u64) {
        if let Some(last) = self.trace.last_mut() {
            last.cycles += cycles;
            self.cycle += cycles;
        }
    }

    /// `a / s` element-wise in f32 on the dividers. A divider is
    /// pipelined: it takes one division a cycle, so the step's `e`
    /// divisions on `d` dividers take one visit of `div1` of
    /// `L_div + ceil(e / d) - 1` cycles.
    fn divide<const R: usize, const C: usize>(
        &mut self,
        step: &'static str,
        a: &SMatrix<f32, R, C>,
        s: f32,
    ) -> SMatrix<f32, R, C> {
        let out = a.map(|v| v / s);
        let elements = R * C;
        let dividers = self.cfg.datapaths.min(self.cfg.dividers);
        let busy = elements.min(dividers);
        let issues = elements.div_ceil(dividers) as u64;
        self.visit(step, State::Div1, self.cfg.latencies.div + issues - 1, busy);
        self.peak.div = self.peak.div.max(busy);
        self.done.div += elements;
        out
    }

    /// Step 4: `inv(O3)` by the determinant `a d - b c` (one datapath:
    /// mult1, mult2, add) and four divisions (`d/det, -b/det, -c/det,
    /// a/det`; negation is a sign-bit flip, free).
    fn inverse2(&mut self, step: &'static str, o3: &Matrix2<f32>) -> Result<Matrix2<f32>, HwError> {
        let det = o3[(0, 0)] * o3[(1, 1)] - o3[(0, 1)] * o3[(1, 0)];
        let l = self.cfg.latencies;
        let states: &[(State, u64)] = if self.cfg.forward {
            &[(State::Mult1, l.mul), (State::Add, l.add)]
        } else {
            &[
                (State::Mult1, l.mul),
                (State::Mult2, 1),
                (State::Add, l.add),
            ]
        };
        self.charge(
            step,
            1,
            states,
            OpCounts {
                mul: 2,
                add: 1,
                div: 0,
            },
        );
        if det == 0.0 || !det.is_finite() {
            return Err(HwError::Numeric("O3 is singular: det(O3) = 0"));
        }
        let adj = Matrix2::new(o3[(1, 1)], -o3[(0, 1)], -o3[(1, 0)], o3[(0, 0)]);
        Ok(self.divide(step, &adj, det))
    }

    fn finish(
        self,
        x_post: Vector3<f32>,
        p_post: Matrix3<f32>,
        gain: Matrix3x2<f32>,
    ) -> Result<CoreRun, HwError> {
        if !(x_post.iter().all(|v| v.is_finite()) && p_post.iter().all(|v| v.is_finite())) {
            return Err(HwError::Numeric("a result is not finite"));
        }
        Ok(CoreRun {
            x_post,
            p_post,
            gain,
            cycles: self.cycle,
            time_s: self.cycle as f64 / self.cfg.clock_hz,
            operators: self.peak,
            operations: self.done,
            trace: self.trace,
        })
    }
}

/// `a b` with each element `((a0 b0 + a1 b1) + a2 b2)` in f32, the order
/// of the core's datapaths.
fn product<const R: usize, const K: usize, const C: usize>(
    a: &SMatrix<f32, R, K>,
    b: &SMatrix<f32, K, C>,
) -> SMatrix<f32, R, C> {
    SMatrix::<f32, R, C>::from_fn(|i, j| {
        let mut acc = a[(i, 0)] * b[(0, j)];
        for k in 1..K {
            acc += a[(i, k)] * b[(k, j)];
        }
        acc
    })
}

/// Runs one correction on the modelled core: the arithmetic in f32 in the
/// schedule's order, and the cycles of every state visit.
///
/// Errors: an invalid configuration, a singular `O3` (or a non-positive
/// scalar innovation variance), a non-finite result.
pub fn run(cfg: &HwConfig, schedule: Schedule, inp: &CoreInputs) -> Result<CoreRun, HwError> {
    cfg.validate()?;
    let mut m = Machine::new(*cfg);
    match schedule {
        Schedule::Inverse2x2 => {
            let o1 = m.matmul("1 O1 = P- H^T", &inp.p, &inp.h.transpose());
            let o2 = m.matmul("2 O2 = H O1", &inp.h, &o1);
            let o3 = m.addsub("3 O3 = O2 + R", &o2, &inp.r, false);
            let o4 = m.inverse2("4 O4 = inv(O3)", &o3)?;
            let g = m.matmul("5 G = O1 O4", &o1, &o4);
            if cfg.overlap && cfg.datapaths >= 6 {
                // Steps 6-8 inside the waves of steps 1, 9 and 10 (the
                // values as computed in the schedule's order); each 3x3
                // step one wave, its row 2 a second group when it needs one.
                let group2 = cfg.datapaths < 9;
                let o5 = inp.z - inp.hx;
                let o6 = product(&g, &o5);
                let x = inp.x + o6;
                m.beside(OpCounts {
                    mul: 6,
                    add: 2 + 3 + 3,
                    div: 0,
                });
                m.one_wave = true;
                let o7 = m.matmul("9 O7 = G H, 7 O6 = G O5", &g, &inp.h);
                m.extend_last(2);
                let o8 = m.matmul("10 O8 = O7 P-, 8 X+ = X- + O6", &o7, &inp.p);
                if group2 {
                    m.extend_last(cfg.latencies.add + 1);
                }
                let p = m.addsub("11 P+ = P- - O8", &inp.p, &o8, true);
                if group2 {
                    m.extend_last(1);
                }
                m.one_wave = false;
                m.finish(x, p, g)
            } else {
                let o5 = m.addsub("6 O5 = z - h(X-)", &inp.z, &inp.hx, true);
                let o6 = m.matmul("7 O6 = G O5", &g, &o5);
                let x = m.addsub("8 X+ = X- + O6", &inp.x, &o6, false);
                let o7 = m.matmul("9 O7 = G H", &g, &inp.h);
                let o8 = m.matmul("10 O8 = O7 P-", &o7, &inp.p);
                let p = m.addsub("11 P+ = P- - O8", &inp.p, &o8, true);
                m.finish(x, p, g)
            }
        }
        Schedule::Scalar => {
            if inp.r[(0, 1)] != 0.0 || inp.r[(1, 0)] != 0.0 {
                return Err(HwError::Numeric(
                    "scalar updates need a diagonal R (decorrelate it first)",
                ));
            }
            let mut x = inp.x;
            let mut p = inp.p;
            let mut gain = Matrix3x2::zeros();
            for i in 0..2 {
                let hi = inp.h.fixed_view::<1, 3>(i, 0).into_owned();
                let o1 = m.matmul("s1 O1 = P h_i^T", &p, &hi.transpose());
                let o2 = m.matmul("s2 O2 = h_i O1", &hi, &o1);
                let ri = SMatrix::<f32, 1, 1>::new(inp.r[(i, i)]);
                let o3 = m.addsub("s3 O3 = O2 + r_i", &o2, &ri, false);
                let s = o3[(0, 0)];
                if !(s > 0.0 && s.is_finite()) {
                    return Err(HwError::Numeric("scalar innovation variance <= 0"));
                }
                let g = m.divide("s4 G = O1 / O3", &o1, s);
                gain.set_column(i, &g);
                let zi = SMatrix::<f32, 1, 1>::new(inp.z[i]);
                let hxi = SMatrix::<f32, 1, 1>::new(inp.hx[i]);
                let mut o5 = m.addsub("s5 O5 = z_i - h_i(X-)", &zi, &hxi, true);
                if i > 0 {
                    let d = m.addsub("s5 d = X - X-", &x, &inp.x, true);
                    let hd = m.matmul("s5 h_i d", &hi, &d);
                    o5 = m.addsub("s5 O5 -= h_i d", &o5, &hd, true);
                }
                let o6 = m.matmul("s6 O6 = G O5", &g, &o5);
                x = m.addsub("s7 X = X + O6", &x, &o6, false);
                let o7 = m.matmul("s8 O7 = G h_i", &g, &hi);
                let o8 = m.matmul("s9 O8 = O7 P", &o7, &p);
                p = m.addsub("s10 P = P - O8", &p, &o8, true);
            }
            m.finish(x, p, gain)
        }
    }
}
