//! Noisy sensors of the simulator: quadrature wheel encoders (through the
//! firmware's [`QuadratureDecoder`]), Sharp-type IR range sensors and the IR
//! pair of paper 001, and laser range beams (paper 000).
//!
//! Every sensor takes the map as a wall list `&[Segment<f64>]` and the true
//! pose as `[x, y, theta]` (m, m, rad, world frame), casts its rays with
//! [`locus_models::laser_wall::ray_cast`], and draws all its randomness from a
//! caller-supplied `&mut StdRng`, so a run is reproducible from its seed.
//! A sensor draws the same number of random values whatever its noise level
//! (a zero standard deviation still draws), so turning noise off does not
//! shift the random stream of the other sensors.

use core::f64::consts::FRAC_PI_2;

use locus_core::nalgebra::{Vector2, Vector3};
use locus_models::IrPair;
use locus_models::laser_wall::{BeamLimits, LaserMount, Segment, ray_cast};
use locus_odometry::{Counter, QuadratureDecoder, Wheel};
use rand::RngExt;
use rand::rngs::StdRng;

use crate::noise::gauss;

/// Errors of sensor construction and use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SensorError {
    /// A parameter is outside its valid domain (the message names it).
    #[error("invalid sensor parameter: {0}")]
    InvalidParameter(&'static str),
    /// An input (travel, pose) is NaN or infinite.
    #[error("non-finite sensor input: {0}")]
    NonFinite(&'static str),
}

/// `Ok(())` if `v` is finite and `>= 0`.
fn check_non_negative(v: f64, what: &'static str) -> Result<(), SensorError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(SensorError::InvalidParameter(what))
    }
}

/// The levels `(A, B)` of x4 phase `count mod 4` in the forward order
/// 00, 10, 11, 01 (the order [`QuadratureDecoder`] counts up).
const fn levels_of(count: i64) -> (bool, bool) {
    match count.rem_euclid(4) {
        0 => (false, false),
        1 => (true, false),
        2 => (true, true),
        _ => (false, true),
    }
}

/// What one [`Encoder::set_travel`] / [`Encoder::advance`] fed the decoder.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EncoderStep {
    /// Real x4 edges generated (one level change each), counts.
    pub edges: u64,
    /// Signed net edges (forward positive), counts.
    pub net: i64,
    /// Injected glitches (each flips both channels for one sample: two
    /// invalid transitions for the decoder, no count).
    pub glitches: u32,
}

/// A quadrature encoder on a wheel, decoded by the firmware's
/// [`QuadratureDecoder`] into a wrapping 20-bit counter.
///
/// The true wheel travel (m) is tracked as a fractional count position
/// `travel / dP` (`dP` = [`Wheel::quantum`]); every integer crossed emits one
/// sample of the channel levels `(A, B)` with exactly one channel changed,
/// in order and with direction, so the decoder's count is
/// `floor(travel / dP)` (modulo `2^20`, plus the initial count). The
/// quantisation is the decoder's, not a rounding in the simulator.
///
/// Optional glitches: with probability `glitch_probability` per
/// update, one sample with both channels inverted is inserted and then the
/// true levels are sampled again: the decoder sees two invalid transitions
/// and no count.
#[derive(Debug, Clone, PartialEq)]
pub struct Encoder {
    wheel: Wheel<f64>,
    decoder: QuadratureDecoder,
    /// Cumulative true travel, m.
    travel: f64,
    /// Edges emitted so far (signed), `floor(travel / dP)`.
    emitted: i64,
    glitch_probability: f64,
    glitches: u64,
}

impl Encoder {
    /// An encoder on `wheel` at travel 0, levels 00, counter (20 bits) at 0,
    /// no glitches.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] if the wheel is invalid.
    pub fn new(wheel: Wheel<f64>) -> Result<Self, SensorError> {
        wheel
            .validate()
            .map_err(|_| SensorError::InvalidParameter("encoder wheel"))?;
        Ok(Self {
            wheel,
            decoder: QuadratureDecoder::new(false, false, Counter::paper()),
            travel: 0.0,
            emitted: 0,
            glitch_probability: 0.0,
            glitches: 0,
        })
    }

    /// The same encoder with the counter starting at `count` (bits above 20
    /// dropped), e.g. just below the wrap.
    #[must_use]
    pub fn with_initial_count(mut self, count: u32) -> Self {
        self.decoder.counter_mut().set(count);
        self
    }

    /// The same encoder injecting a glitch with probability `p` per update.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] unless `0 <= p <= 1`.
    pub fn with_glitch_probability(mut self, p: f64) -> Result<Self, SensorError> {
        if !(0.0..=1.0).contains(&p) {
            return Err(SensorError::InvalidParameter(
                "glitch probability must be in [0, 1]",
            ));
        }
        self.glitch_probability = p;
        Ok(self)
    }

    /// The wheel.
    pub const fn wheel(&self) -> &Wheel<f64> {
        &self.wheel
    }

    /// The cumulative true travel, m.
    pub const fn travel(&self) -> f64 {
        self.travel
    }

    /// Moves the wheel by `delta` metres (signed) and feeds the decoder.
    /// See [`set_travel`](Self::set_travel).
    ///
    /// # Errors
    /// [`SensorError::NonFinite`] if the new travel is not finite (nothing
    /// changes).
    pub fn advance(&mut self, delta: f64, rng: &mut StdRng) -> Result<EncoderStep, SensorError> {
        self.set_travel(self.travel + delta, rng)
    }

    /// Sets the wheel's cumulative true travel (m) and feeds the decoder the
    /// level sequence of the motion since the last update: one sample per
    /// x4 edge crossed, in order. Draws one value from `rng` (the glitch
    /// decision) per call, whether or not glitches are enabled.
    ///
    /// # Errors
    /// [`SensorError::NonFinite`] if `travel` is not finite (nothing
    /// changes).
    pub fn set_travel(
        &mut self,
        travel: f64,
        rng: &mut StdRng,
    ) -> Result<EncoderStep, SensorError> {
        if !travel.is_finite() {
            return Err(SensorError::NonFinite("encoder travel"));
        }
        let counts = self.wheel.counts_for(travel).floor();
        // Beyond i64 (~1e18 counts) nothing is meaningful anyway.
        if counts.abs() >= 9.0e18 {
            return Err(SensorError::NonFinite("encoder travel out of range"));
        }
        let target = counts as i64;
        let glitch = rng.random::<f64>() < self.glitch_probability;
        let mut step = EncoderStep::default();
        let forward = target >= self.emitted;
        while self.emitted != target {
            self.emitted += if forward { 1 } else { -1 };
            let (a, b) = levels_of(self.emitted);
            self.decoder.update(a, b);
            step.edges += 1;
        }
        step.net = if forward {
            step.edges as i64
        } else {
            -(step.edges as i64)
        };
        if glitch {
            let (a, b) = levels_of(self.emitted);
            self.decoder.update(!a, !b);
            self.decoder.update(a, b);
            step.glitches = 1;
            self.glitches += 1;
        }
        self.travel = travel;
        Ok(step)
    }

    /// The decoder's wrapping 20-bit count (what the firmware reads).
    pub const fn read(&self) -> u32 {
        self.decoder.counter().value()
    }

    /// The decoder (levels, counter, invalid-transition count).
    pub const fn decoder(&self) -> &QuadratureDecoder {
        &self.decoder
    }

    /// The number of glitches injected so far.
    pub const fn glitches(&self) -> u64 {
        self.glitches
    }
}

/// A Sharp-type IR range sensor (paper 001): the raw reading `A` relates to
/// the distance `D` (m) by
///
/// ```text
/// D = a (C_M / (A + C_R) - b)          A = C_M / (D / a + b) - C_R
/// ```
///
/// \[assumed\] constants ([`SharpIr::assumed`]): `a = 0.01` m/cm,
/// `C_M = 2914`, `C_R = 5`, `b = 1` (the common fit `D[cm] = 2914 / (A + 5) - 1`
/// of a GP2D120 on a 10-bit ADC: `A` ~ 578 at 4 cm, ~ 89 at 30 cm). The raw
/// reading is not quantised to integers. Gaussian noise of standard deviation
/// `sigma` (m) is added to the distance; a reading exists only when the
/// noisy distance is in the useful range `[min_range, max_range]`
/// (\[assumed\] 0.04-0.30 m). The distance is reported as a 32-bit float,
/// as the robot link and the log format carry it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SharpIr {
    /// Scale `a` (m per curve unit, > 0).
    pub a: f64,
    /// Curve constant `C_M` (> 0).
    pub c_m: f64,
    /// Curve offset `C_R` (reading units).
    pub c_r: f64,
    /// Curve offset `b` (curve units).
    pub b: f64,
    /// Standard deviation of the distance noise (m, >= 0).
    pub sigma: f64,
    /// Smallest distance read (m).
    pub min_range: f64,
    /// Largest distance read (m).
    pub max_range: f64,
}

impl SharpIr {
    /// The \[assumed\] sensor (see the type doc) with distance noise `sigma` (m).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] if `sigma` is negative or not finite.
    pub fn assumed(sigma: f64) -> Result<Self, SensorError> {
        Self {
            a: 0.01,
            c_m: 2914.0,
            c_r: 5.0,
            b: 1.0,
            sigma,
            min_range: 0.04,
            max_range: 0.30,
        }
        .validated()
    }

    /// `Ok(self)` if the constants are finite, `a, C_M > 0`, `sigma >= 0` and
    /// `0 < min_range < max_range`, with `D / a + b > 0` over the range.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] naming the first bad field.
    pub fn validated(self) -> Result<Self, SensorError> {
        let bad = SensorError::InvalidParameter;
        if !(self.a.is_finite() && self.a > 0.0) {
            return Err(bad("IR scale a must be finite and > 0"));
        }
        if !(self.c_m.is_finite() && self.c_m > 0.0) {
            return Err(bad("IR constant C_M must be finite and > 0"));
        }
        if !(self.c_r.is_finite() && self.b.is_finite()) {
            return Err(bad("IR offsets C_R, b must be finite"));
        }
        check_non_negative(self.sigma, "IR sigma must be finite and >= 0")?;
        if !(self.min_range > 0.0 && self.min_range < self.max_range && self.max_range.is_finite())
        {
            return Err(bad("IR range must satisfy 0 < min < max"));
        }
        if self.min_range / self.a + self.b <= 0.0 {
            return Err(bad("IR curve singular in the useful range"));
        }
        Ok(self)
    }

    /// The raw reading `A = C_M / (D / a + b) - C_R` for a distance `D` (m).
    pub fn raw_from_distance(&self, distance: f64) -> f64 {
        self.c_m / (distance / self.a + self.b) - self.c_r
    }

    /// The distance `D = a (C_M / (A + C_R) - b)` (m) for a raw reading `A`.
    pub fn distance_from_raw(&self, raw: f64) -> f64 {
        self.a * (self.c_m / (raw + self.c_r) - self.b)
    }

    /// A noisy raw reading for the true distance `distance` (m), or `None`
    /// when the noisy distance is outside the useful range (or not finite).
    /// Draws one value from `rng`.
    pub fn read_raw(&self, distance: f64, rng: &mut StdRng) -> Option<f64> {
        let noisy = distance + gauss(rng, self.sigma);
        (noisy >= self.min_range && noisy <= self.max_range).then(|| self.raw_from_distance(noisy))
    }

    /// A noisy reading converted back to distance through the curve (m), as
    /// the firmware reports it; `None` as for [`read_raw`](Self::read_raw).
    pub fn read(&self, distance: f64, rng: &mut StdRng) -> Option<f64> {
        self.reading(distance, rng).distance()
    }

    /// What the sensor reads for the true distance `distance` (m): the
    /// reading of [`read`](Self::read), or why there is none (the noisy
    /// distance beyond the useful range, or not finite: no return; below
    /// it: no valid reading). Draws one value from `rng`, as `read` does.
    pub fn reading(&self, distance: f64, rng: &mut StdRng) -> IrReading {
        let noisy = distance + gauss(rng, self.sigma);
        self.classify(noisy)
    }

    /// The reading of a noisy distance `noisy` (m): through the curve in
    /// the useful range, else [`IrReading::Beyond`] (above it, or not a
    /// number) or [`IrReading::Below`].
    pub fn classify(&self, noisy: f64) -> IrReading {
        if noisy >= self.min_range && noisy <= self.max_range {
            // Reported as a 32-bit float, as the robot link (docs/protocol.md)
            // and the log format carry it, so that a run written as a log
            // replays with the very readings the loop corrected with.
            let distance = self.distance_from_raw(self.raw_from_distance(noisy));
            #[allow(clippy::cast_possible_truncation)]
            IrReading::Distance(f64::from(distance as f32))
        } else if noisy < self.min_range {
            IrReading::Below
        } else {
            IrReading::Beyond
        }
    }
}

/// What one IR sensor read in a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum IrReading {
    /// A distance in the useful range, m.
    Distance(f64),
    /// Nothing within the useful range: no return (the wall beyond it, or
    /// no wall along the beam).
    Beyond,
    /// Closer than the useful range: no valid reading.
    Below,
}

impl IrReading {
    /// The distance, if the sensor read one (m).
    #[must_use]
    pub fn distance(self) -> Option<f64> {
        match self {
            IrReading::Distance(d) => Some(d),
            IrReading::Beyond | IrReading::Below => None,
        }
    }
}

/// Casts a beam of `mount` from the robot at `pose` on `walls`; the range (m)
/// to the nearest wall within `max_range`, or `None`.
///
/// # Errors
/// [`SensorError::NonFinite`] if the pose is not finite.
pub fn cast_beam(
    walls: &[Segment<f64>],
    pose: [f64; 3],
    mount: &LaserMount<f64>,
    max_range: f64,
) -> Result<Option<f64>, SensorError> {
    if !pose.iter().all(|v| v.is_finite()) {
        return Err(SensorError::NonFinite("robot pose"));
    }
    let x = Vector3::from(pose);
    let p_s: Vector2<f64> = mount.sensor_position(&x);
    let u = mount.beam_direction(pose[2]);
    let limits = BeamLimits::with_max_range(max_range);
    Ok(ray_cast(&p_s, &u, walls, &limits).map(|h| h.hit.range))
}

/// The IR pair of paper 001 on the robot's right side: two [`SharpIr`]
/// sensors pointing right (beam angle `-pi/2`), `L` apart along the heading,
/// `s1` in front, their centre `e` to the right of and `c` ahead of the
/// robot centre ([`IrPair`]). Sensor `s1` sits at `(c + L/2, -e)`, `s2` at
/// `(c - L/2, -e)` in the robot frame (x ahead, y left).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IrPairSensor {
    /// The mounting (`L`, `e`, `c`, m).
    pub pair: IrPair<f64>,
    /// The front sensor `s1`.
    pub front: SharpIr,
    /// The rear sensor `s2`.
    pub rear: SharpIr,
}

impl IrPairSensor {
    /// A pair of identical `sensor`s mounted as `pair`.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] if the spacing is not finite and
    /// > 0, or an offset is not finite.
    pub fn new(pair: IrPair<f64>, sensor: SharpIr) -> Result<Self, SensorError> {
        if !(pair.spacing.is_finite() && pair.spacing > 0.0) {
            return Err(SensorError::InvalidParameter(
                "IR spacing must be finite and > 0",
            ));
        }
        if !(pair.lateral_offset.is_finite() && pair.forward_offset.is_finite()) {
            return Err(SensorError::InvalidParameter("IR offsets must be finite"));
        }
        Ok(Self {
            pair,
            front: sensor,
            rear: sensor,
        })
    }

    /// The mountings of `s1` and `s2` as beams (robot frame).
    pub fn mounts(&self) -> [LaserMount<f64>; 2] {
        let half = 0.5 * self.pair.spacing;
        let c = self.pair.forward_offset;
        let y = -self.pair.lateral_offset;
        [
            LaserMount::new(c + half, y, -FRAC_PI_2),
            LaserMount::new(c - half, y, -FRAC_PI_2),
        ]
    }

    /// The true (noise-free) distances `(d_s1, d_s2)` to the walls along the
    /// two beams (m), each `None` if its beam hits no wall.
    ///
    /// # Errors
    /// [`SensorError::NonFinite`] if the pose is not finite.
    pub fn true_distances(
        &self,
        walls: &[Segment<f64>],
        pose: [f64; 3],
    ) -> Result<(Option<f64>, Option<f64>), SensorError> {
        let [m1, m2] = self.mounts();
        Ok((
            cast_beam(walls, pose, &m1, f64::INFINITY)?,
            cast_beam(walls, pose, &m2, f64::INFINITY)?,
        ))
    }

    /// The noisy readings `(d_s1, d_s2)` (m, through each sensor's curve),
    /// only when both are valid (in the useful range). Draws exactly two
    /// values from `rng` (s1 then s2) whether or not the beams hit.
    ///
    /// # Errors
    /// [`SensorError::NonFinite`] if the pose is not finite.
    pub fn read(
        &self,
        walls: &[Segment<f64>],
        pose: [f64; 3],
        rng: &mut StdRng,
    ) -> Result<Option<(f64, f64)>, SensorError> {
        let [r1, r2] = self.read_each(walls, pose, rng)?;
        Ok(r1.distance().zip(r2.distance()))
    }

    /// What each sensor read, `[s1, s2]`: the readings [`read`](Self::read)
    /// pairs (the same two draws from `rng`, s1 then s2), with why a
    /// sensor read nothing.
    ///
    /// # Errors
    /// [`SensorError::NonFinite`] if the pose is not finite.
    pub fn read_each(
        &self,
        walls: &[Segment<f64>],
        pose: [f64; 3],
        rng: &mut StdRng,
    ) -> Result<[IrReading; 2], SensorError> {
        let (t1, t2) = self.true_distances(walls, pose)?;
        // Far beyond any useful range: the sensor reads nothing.
        let r1 = self.front.reading(t1.unwrap_or(f64::INFINITY), rng);
        let r2 = self.rear.reading(t2.unwrap_or(f64::INFINITY), rng);
        Ok([r1, r2])
    }
}

/// A laser range finder of one or more beams (paper 000): each beam is a
/// [`LaserMount`] (`x_si`, `y_si`, `beta_i`), cast on the walls; the true
/// range plus Gaussian noise of standard deviation `sigma` (m), clamped at 0,
/// or `None` when the beam hits nothing within `max_range` (judged on the
/// true range).
#[derive(Debug, Clone, PartialEq)]
pub struct Laser {
    /// The beams' mountings.
    pub beams: Vec<LaserMount<f64>>,
    /// Standard deviation of the range noise (m, >= 0).
    pub sigma: f64,
    /// Largest range returned (m, > 0).
    pub max_range: f64,
}

impl Laser {
    /// A laser with `beams`, range noise `sigma` (m) and `max_range` (m).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] if `sigma` is negative or not
    /// finite, or `max_range` is not > 0.
    pub fn new(
        beams: Vec<LaserMount<f64>>,
        sigma: f64,
        max_range: f64,
    ) -> Result<Self, SensorError> {
        check_non_negative(sigma, "laser sigma must be finite and >= 0")?;
        if max_range.is_nan() || max_range <= 0.0 {
            return Err(SensorError::InvalidParameter("laser max range must be > 0"));
        }
        Ok(Self {
            beams,
            sigma,
            max_range,
        })
    }

    /// The noisy range of each beam (m) in order, `None` for a beam that hits
    /// nothing. Draws exactly one value per beam from `rng`.
    ///
    /// # Errors
    /// [`SensorError::NonFinite`] if the pose is not finite.
    pub fn read(
        &self,
        walls: &[Segment<f64>],
        pose: [f64; 3],
        rng: &mut StdRng,
    ) -> Result<Vec<Option<f64>>, SensorError> {
        self.beams
            .iter()
            .map(|m| {
                let range = cast_beam(walls, pose, m, self.max_range)?;
                let noise = gauss(rng, self.sigma);
                Ok(range.map(|r| (r + noise).max(0.0)))
            })
            .collect()
    }
}
