//! The firmware's application, `no_std` and allocation-free: x4 quadrature
//! decoding of two wheels, the differential-drive EKF of paper 001 with IR
//! wall corrections, and a CORDIC dead-reckoning pose (paper 004), all in
//! `f32`, over a recorded sequence ([`square_data`], generated from the
//! simulator's `square` scenario).
//!
//! The same code runs in the Cortex-M4F firmware (`locus-fw`, under QEMU) and
//! on the host in this crate's tests; both are built in the firmware
//! workspace, where the filter's crates have no `std` feature, so every
//! `sin`, `cos`, `atan`, `sqrt` and `floor` comes from the `libm` crate and
//! the two runs are bit-identical (IEEE-754 single precision, round to
//! nearest, no fused multiply-add: Rust never contracts `a * b + c`).
//!
//! One step of `dt` = 10 ms ([`Firmware::step`]) runs paper 001's
//! localisation loop as [`locus_models::square001`] has it, once for every
//! loop of Locus ([`Localiser`]: the running filter, [`DiffDrive`], the
//! [`Odometer`] and the [`IrAssociation`]); the firmware only supplies the
//! counts, the readings and the arena:
//! 1. [`Firmware::decode`]: the step's [`SAMPLES_PER_STEP`] samples of the
//!    channel levels `(A, B)` of the right and left encoders go through a
//!    [`QuadratureDecoder`] each (20-bit wrapping counters, paper 004
//!    section 2.1); the localiser's [`Odometer`] turns the counts into the
//!    wheel travels `d1` (right), `d2` (left) of paper 001 eq. 9 (wrapping
//!    count differences times the count quantum `dP = pi R / (2 N G)`).
//! 2. [`Firmware::filter_step`]: prediction with [`DiffDrive`] (paper 001
//!    eq. 7-13, [`Firmware::predict`]); if the step has an IR reading,
//!    [`Firmware::correct`]: [`Localiser::ir`] on [`square_data::ARENA`]
//!    associates it on the predicted pose ([`associate_ir_wall`]) and, for
//!    an axis-aligned wall, corrects with [`IrPairObservation`] (eq. 3-5,
//!    17-20), Joseph form, behind a 99 % chi-square gate on the NIS (a
//!    [`ChiSquareGate::from_threshold`] with the threshold precomputed on the
//!    host, see [`Config::gate_threshold`]).
//! 3. [`Firmware::odometry_step`]: the odometry-only pose advanced by the
//!    same wheel travels, midpoint heading, with the sine and cosine from the
//!    paper's 16-bit, 16-iteration [`Cordic`] (paper 004 section 4.1).
//! 4. The step's state is folded into an FNV-1a checksum ([`Checksum`]): the
//!    `f32` bit patterns of `x`, `P` (row-major, all nine entries) and the
//!    odometry pose.
//!
//! [`associate_ir_wall`]: locus_models::associate_ir_wall
#![no_std]
#![forbid(unsafe_code)]

pub mod link;
pub mod square_data;

use locus_core::nalgebra::{Matrix3, Vector3};
use locus_core::{Belief, ChiSquareGate, CovarianceUpdate, Ekf, Pose, Update};
use locus_models::{
    DiffDrive, IrAssociation, IrOutcome, IrPair, IrPairObservation, Localiser, Odometer,
    WheelTravel,
};
use locus_odometry::redundant::{Integration, Motion};
use locus_odometry::{Cordic, Counter, QuadratureDecoder, Wheel};

/// Samples of the channel levels per filter step (the decoder runs at
/// `SAMPLES_PER_STEP / dt`, 800 Hz for 10 ms steps). Each sample is a nibble
/// of a step's `u32` in [`square_data::WAVEFORM`]: bit 0 right A, bit 1
/// right B, bit 2 left A, bit 3 left B; sample 0 in the lowest nibble.
pub const SAMPLES_PER_STEP: usize = 8;

/// The parameters of a run (SI units; variances per filter step), as the
/// generator wrote them from the simulator's `SquareConfig` (`f64` rounded
/// to the nearest `f32`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// Distance between the wheels `b`, m.
    pub wheelbase: f32,
    /// Wheel radius `R`, m.
    pub wheel_radius: f32,
    /// Encoder lines `N` per shaft revolution (gear `G` = 1).
    pub encoder_lines: u32,
    /// `Q11 = var(e_d)`, m^2.
    pub q11: f32,
    /// `Q22 = var(e_dtheta)`, rad^2.
    pub q22: f32,
    /// `R11 = var(e_ds1)`, m^2.
    pub r11: f32,
    /// `R22 = var(e_ds2)`, m^2.
    pub r22: f32,
    /// IR pair spacing `L`, m (pair centred on the robot).
    pub ir_spacing: f32,
    /// Largest pair-to-wall distance accepted by the data association, m.
    pub association_range: f32,
    /// Confidence of the chi-square gate on the NIS.
    pub gate_confidence: f64,
    /// The gate's threshold for the IR pair's 2 degrees of freedom,
    /// `chi2_2(gate_confidence)` computed on the host by
    /// `locus_core::chi2::quantile` and rounded to `f32`: exactly what
    /// `ChiSquareGate::<f32>::new(gate_confidence).threshold(2)` holds (the
    /// tests check it), without the quantile's `f64` special functions in
    /// the firmware.
    pub gate_threshold: f32,
    /// Initial estimate `[x, y, theta]`, m, m, rad.
    pub start: [f32; 3],
    /// Standard deviations of the initial estimate, m, m, rad.
    pub initial_std: [f32; 3],
}

/// An error of the run: the filter rejected its input or the configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Error {
    /// The filter failed at step `step` (0-based).
    Filter {
        /// The step.
        step: u32,
        /// The filter's error.
        error: locus_core::Error,
    },
    /// The configuration is invalid (the gate's threshold or confidence).
    Config(locus_core::Error),
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Filter { step, error } => write!(f, "filter error at step {step}: {error}"),
            Error::Config(e) => write!(f, "invalid configuration: {e}"),
        }
    }
}

/// 32-bit FNV-1a over bytes (offset basis `0x811c9dc5`, prime `0x01000193`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Checksum(pub u32);

impl Default for Checksum {
    fn default() -> Self {
        Self(0x811c_9dc5)
    }
}

impl Checksum {
    /// Folds the four little-endian bytes of `word` into the checksum.
    #[inline]
    pub fn word(&mut self, word: u32) {
        for b in word.to_le_bytes() {
            self.0 = (self.0 ^ u32::from(b)).wrapping_mul(0x0100_0193);
        }
    }

    /// Folds the bit pattern of each value.
    #[inline]
    pub fn floats(&mut self, values: &[f32]) {
        for v in values {
            self.word(v.to_bits());
        }
    }
}

/// What [`Firmware::correct`] did with an IR reading: which of the run's
/// counts it moved.
///
/// The localiser's own answer, [`IrOutcome`] (the observation and the
/// typed update: NIS, `S`, gain, posterior and a possible first attempt,
/// 256 bytes), is read inside [`Firmware::correct`] and not handed on:
/// returning it by value cost about 600 instructions per correction and
/// 216 bytes of stack on the Cortex-M4F, and the step needs only this.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reading {
    /// No axis-aligned wall in range along the sensing ray: dropped.
    Unassociated,
    /// Associated, and the correction was applied.
    Corrected,
    /// Associated, and the gate rejected the correction.
    Rejected,
}

/// What the run reports: the final belief and odometry pose, the checksum of
/// every step's state, and counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Report {
    /// Steps run.
    pub steps: u32,
    /// Final EKF mean `[x, y, theta]` (m, m, rad).
    pub x: [f32; 3],
    /// Final EKF covariance, row-major (m^2, m rad, rad^2).
    pub p: [f32; 9],
    /// Final odometry-only (CORDIC) pose `[x, y, theta]`.
    pub odometry: [f32; 3],
    /// FNV-1a of every step's `x`, `P`, odometry pose bits.
    pub checksum: u32,
    /// Corrections applied.
    pub corrections: u32,
    /// Corrections rejected by the gate.
    pub rejected: u32,
    /// IR readings dropped by the data association (no axis-aligned wall in
    /// range).
    pub unassociated: u32,
    /// Invalid quadrature transitions (both channels changed), both wheels.
    pub invalid_transitions: u32,
    /// Final wrapping 20-bit counts `[right, left]`.
    pub counts: [u32; 2],
}

impl Report {
    /// Every `f32` of the report with its name, in print order (the firmware
    /// prints these bit patterns; the host test parses them).
    pub fn floats(&self) -> [(&'static str, f32); 15] {
        let [x, y, th] = self.x;
        let p = self.p;
        let [ox, oy, oth] = self.odometry;
        [
            ("x", x),
            ("y", y),
            ("theta", th),
            ("p00", p[0]),
            ("p01", p[1]),
            ("p02", p[2]),
            ("p10", p[3]),
            ("p11", p[4]),
            ("p12", p[5]),
            ("p20", p[6]),
            ("p21", p[7]),
            ("p22", p[8]),
            ("odo_x", ox),
            ("odo_y", oy),
            ("odo_theta", oth),
        ]
    }

    /// Every integer of the report with its name, in print order.
    pub fn integers(&self) -> [(&'static str, u32); 8] {
        [
            ("steps", self.steps),
            ("checksum", self.checksum),
            ("corrections", self.corrections),
            ("rejected", self.rejected),
            ("unassociated", self.unassociated),
            ("invalid_transitions", self.invalid_transitions),
            ("count_right", self.counts[0]),
            ("count_left", self.counts[1]),
        ]
    }
}

/// The firmware's whole state: the decoders, paper 001's [`Localiser`]
/// (belief, gate, NIS monitor, drive model, odometer, IR association), the
/// odometry pose, the checksum and the counts. Plain data, lives on the
/// stack.
#[derive(Debug, Clone)]
pub struct Firmware {
    localiser: Localiser<f32>,
    cordic: Cordic,
    right: QuadratureDecoder,
    left: QuadratureDecoder,
    odometry: Pose<f32>,
    checksum: Checksum,
    steps: u32,
    corrections: u32,
    rejected: u32,
    unassociated: u32,
}

impl Firmware {
    /// The state at the start of a run: decoders at levels 00 and count 0
    /// (the odometer's reference), belief `N(start, diag(initial_std^2))`,
    /// odometry pose at `start`.
    ///
    /// The correction is gated on the configuration's precomputed 2-dof
    /// threshold ([`ChiSquareGate::from_threshold`]), so the firmware
    /// carries no chi-square quantile; [`Firmware::with_library_gate`]
    /// computes the gate from the confidence instead, and the tests check
    /// that both give the same run bit for bit.
    ///
    /// # Errors
    /// [`Error::Config`] for a gate threshold that is not > 0 (NaN
    /// included).
    #[inline(never)]
    pub fn new(cfg: &Config) -> Result<Self, Error> {
        let gate = ChiSquareGate::from_threshold(2, cfg.gate_threshold).map_err(Error::Config)?;
        Ok(Self::with_gate(cfg, gate))
    }

    /// As [`Firmware::new`], but with the gate computed here from
    /// `gate_confidence` ([`ChiSquareGate::new`]: the chi-square quantile in
    /// `f64`) instead of the precomputed threshold: the reference the tests
    /// compare against.
    ///
    /// # Errors
    /// [`Error::Config`] for a gate confidence outside (0, 1).
    pub fn with_library_gate(cfg: &Config) -> Result<Self, Error> {
        let gate = ChiSquareGate::new(cfg.gate_confidence).map_err(Error::Config)?;
        Ok(Self::with_gate(cfg, gate))
    }

    #[inline(always)]
    fn with_gate(cfg: &Config, gate: ChiSquareGate<f32>) -> Self {
        let [s0, s1, s2] = cfg.start;
        let [d0, d1, d2] = cfg.initial_std;
        let belief = Belief::new(
            Vector3::new(s0, s1, s2),
            Matrix3::from_diagonal(&Vector3::new(d0 * d0, d1 * d1, d2 * d2)),
        );
        let odometer = Odometer::new(
            Wheel::new(cfg.encoder_lines, 1.0, cfg.wheel_radius),
            Counter::paper().bits(),
        )
        .with_reference([0, 0]);
        let ir = IrAssociation {
            pair: IrPair::centred(cfg.ir_spacing),
            range: cfg.association_range,
            r11: cfg.r11,
            r22: cfg.r22,
        };
        Self {
            localiser: Localiser::new(
                Ekf::new(CovarianceUpdate::Joseph).with_gate(gate),
                belief,
                DiffDrive::new(cfg.wheelbase, cfg.q11, cfg.q22),
                odometer,
                ir,
            ),
            cordic: Cordic::PAPER,
            right: QuadratureDecoder::new(false, false, Counter::paper()),
            left: QuadratureDecoder::new(false, false, Counter::paper()),
            odometry: Pose::new(s0, s1, s2),
            checksum: Checksum::default(),
            steps: 0,
            corrections: 0,
            rejected: 0,
            unassociated: 0,
        }
    }

    /// Decodes one step's [`SAMPLES_PER_STEP`] level samples (nibbles of
    /// `samples`, see [`SAMPLES_PER_STEP`]) and returns the wheel travels of
    /// the step from the localiser's [`Odometer`] (m; paper 001 eq. 9,
    /// `d_i = counts_i dP`, wrap-safe on the 20-bit counters).
    #[inline(never)]
    pub fn decode(&mut self, samples: u32) -> WheelTravel<f32> {
        for k in 0..SAMPLES_PER_STEP {
            let nibble = samples >> (4 * k);
            self.right.update(nibble & 1 != 0, nibble & 2 != 0);
            self.left.update(nibble & 4 != 0, nibble & 8 != 0);
        }
        let now = [self.right.counter().value(), self.left.counter().value()];
        // The odometer has had its reference since `new`, so it always
        // answers; no travel is the only sensible value otherwise.
        self.localiser
            .odometer
            .travel(now)
            .unwrap_or(WheelTravel { d1: 0.0, d2: 0.0 })
    }

    /// The filter step: [`predict`](Self::predict) with the wheel travels
    /// `u`, then, if the step has IR readings `ir = [d_s1, d_s2]` (m),
    /// [`correct`](Self::correct).
    ///
    /// # Errors
    /// [`Error::Filter`] if the filter rejects an input (the belief is then
    /// unchanged).
    pub fn filter_step(&mut self, u: &WheelTravel<f32>, ir: Option<[f32; 2]>) -> Result<(), Error> {
        self.predict(u)?;
        if let Some(readings) = ir {
            self.correct(readings)?;
        }
        Ok(())
    }

    /// Prediction with [`DiffDrive`] (paper 001 eq. 7-13,
    /// [`Localiser::predict`]): `X- = f(X+, u, 0)`,
    /// `P- = A P+ A^T + W Q W^T`.
    ///
    /// # Errors
    /// [`Error::Filter`] for a non-finite input (the belief is unchanged).
    #[inline(never)]
    pub fn predict(&mut self, u: &WheelTravel<f32>) -> Result<(), Error> {
        let step = self.steps;
        self.localiser
            .predict(u)
            .map_err(|error| Error::Filter { step, error })
    }

    /// An IR reading `[d_s1, d_s2]` (m): [`Localiser::ir`] on the arena
    /// ([`square_data::ARENA`]): the wall the pair's sensing ray hits from
    /// the current (predicted) pose within `association_range`
    /// ([`locus_models::associate_ir_wall`]; none: the reading is dropped
    /// and counted as unassociated), then the correction with [`IrPairObservation`]
    /// (paper 001 eq. 3-5 for `z`, eq. 17-20 for `H` and `V R V^T`),
    /// `S = H P H^T + V R V^T`, `G = P H^T S^-1`, Joseph form, kept only if
    /// the NIS passes the gate (counted as a correction or a rejection).
    ///
    /// # Errors
    /// [`Error::Filter`] if the filter rejects the measurement, or predicts
    /// none (the belief is unchanged).
    #[inline(never)]
    pub fn correct(&mut self, readings: [f32; 2]) -> Result<Reading, Error> {
        let step = self.steps;
        let outcome = self
            .localiser
            .ir(&square_data::ARENA, readings)
            .map_err(|error| Error::Filter { step, error })?;
        Ok(match outcome {
            IrOutcome::Unassociated => {
                self.unassociated += 1;
                Reading::Unassociated
            }
            IrOutcome::Associated { update, .. } => match update {
                Update::Applied { .. } => {
                    self.corrections += 1;
                    Reading::Corrected
                }
                Update::Gated { .. } => {
                    self.rejected += 1;
                    Reading::Rejected
                }
                // The IR pair predicts a measurement at every state; as the
                // filter's error it stops the run, as any other would.
                Update::NoMeasurement => {
                    return Err(Error::Filter {
                        step,
                        error: locus_core::Error::NoMeasurement,
                    });
                }
            },
        })
    }

    /// The data association alone, as [`correct`](Self::correct) does it
    /// first: the observation of the readings `[d_s1, d_s2]` (m) of the wall
    /// the estimate's sensing ray hits ([`IrAssociation::observe`] on
    /// [`square_data::ARENA`]), or `None`. Changes nothing; the firmware
    /// binary times it to split a correction's cost.
    #[inline(never)]
    pub fn associate(&self, readings: [f32; 2]) -> Option<IrPairObservation<f32>> {
        self.localiser
            .ir
            .observe(&self.localiser.belief().x, &square_data::ARENA, readings)
    }

    /// Advances the odometry-only pose by the wheel travels `u`: path length
    /// `(d1 + d2) / 2`, heading change `(d1 - d2) / b` (paper 001 eq. 8),
    /// midpoint heading, sine and cosine by the [`Cordic`].
    #[inline(never)]
    pub fn odometry_step(&mut self, u: &WheelTravel<f32>) {
        let (ds, dtheta) = self.localiser.model.increments(u);
        let inc = Motion { ds, dtheta }.increment(
            self.odometry.theta,
            Integration::Midpoint,
            &self.cordic,
        );
        self.odometry = inc.apply(&self.odometry);
    }

    /// Folds the current state into the checksum and counts the step.
    #[inline(never)]
    pub fn finish_step(&mut self) {
        let belief = self.localiser.belief();
        self.checksum.floats(belief.x.as_slice());
        self.checksum.floats(belief.p.transpose().as_slice());
        let o = self.odometry;
        self.checksum.floats(&[o.x, o.y, o.theta]);
        self.steps += 1;
    }

    /// One whole step: [`decode`](Self::decode),
    /// [`filter_step`](Self::filter_step),
    /// [`odometry_step`](Self::odometry_step),
    /// [`finish_step`](Self::finish_step).
    ///
    /// # Errors
    /// As [`filter_step`](Self::filter_step).
    pub fn step(&mut self, samples: u32, ir: Option<[f32; 2]>) -> Result<(), Error> {
        let u = self.decode(samples);
        self.filter_step(&u, ir)?;
        self.odometry_step(&u);
        self.finish_step();
        Ok(())
    }

    /// The decoders' wrapping 20-bit counts `[right, left]` now (what the
    /// link robot extends to the link's 32-bit counts).
    pub fn counts(&self) -> [u32; 2] {
        [self.right.counter().value(), self.left.counter().value()]
    }

    /// The current belief.
    pub fn belief(&self) -> &Belief<f32, 3> {
        self.localiser.belief()
    }

    /// The localiser (its running filter holds the gate and the NIS
    /// consistency monitor).
    pub fn localiser(&self) -> &Localiser<f32> {
        &self.localiser
    }

    /// The report of the run so far.
    pub fn report(&self) -> Report {
        let belief = self.localiser.belief();
        let x = belief.x;
        let pt = belief.p.transpose(); // column-major storage: rows of P
        let mut p = [0.0f32; 9];
        p.copy_from_slice(pt.as_slice());
        Report {
            steps: self.steps,
            x: [x[0], x[1], x[2]],
            p,
            odometry: [self.odometry.x, self.odometry.y, self.odometry.theta],
            checksum: self.checksum.0,
            corrections: self.corrections,
            rejected: self.rejected,
            unassociated: self.unassociated,
            invalid_transitions: self.right.invalid_transitions() + self.left.invalid_transitions(),
            counts: [self.right.counter().value(), self.left.counter().value()],
        }
    }
}

/// Runs the whole embedded sequence ([`square_data`]) and reports.
///
/// # Errors
/// As [`Firmware::new`] and [`Firmware::step`].
pub fn run() -> Result<Report, Error> {
    run_with(Firmware::new(&square_data::CONFIG)?)
}

/// Runs the whole embedded sequence from the state `fw`.
///
/// # Errors
/// As [`Firmware::step`].
pub fn run_with(mut fw: Firmware) -> Result<Report, Error> {
    for (samples, ir) in square_data::WAVEFORM.iter().zip(square_data::IR.iter()) {
        fw.step(*samples, *ir)?;
    }
    Ok(fw.report())
}
