//! Paper 001's localisation loop, once: encoder counts -> wheel travel ->
//! prediction ([`DiffDrive`], eq. 7-13) -> IR pair -> wall association
//! ([`associate_ir_wall`]) -> correction ([`IrPairObservation`], eq. 3-5,
//! 17-20) behind the gate of the [`RunningFilter`].
//!
//! The simulator, the robot-link host, the firmware, `locus demo` and the
//! teaching UI all run [`Localiser`]; they differ only in where the counts
//! and readings come from.
//!
//! * [`Odometer`]: wrapping encoder counts (of a counter `bits` wide: 20 on
//!   paper 004's decoder, 32 on the robot link) -> signed count differences
//!   -> wheel travels `d1` (right), `d2` (left) in m (paper 001 eq. 9:
//!   `d_i = counts_i dP`).
//! * [`IrAssociation`]: the IR pair's mounting, the association range and
//!   `R`; turns a reading `[d_s1, d_s2]` (m) into an observation of the wall
//!   the estimate's sensing ray hits, or `None` (dropped).

use locus_core::{Ekf, Error, Recovery, Rules, RunningFilter, Scalar, Update};
use locus_odometry::{Real, Wheel, wrapping_diff};

use crate::{DiffDrive, IrPair, IrPairObservation, Segment, WheelTravel, associate_ir_wall};

/// Encoder counts -> wheel travels, wrap-safe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Odometer<T> {
    wheel: Wheel<T>,
    bits: u32,
    last: Option<[u32; 2]>,
}

impl<T: Real> Odometer<T> {
    /// An odometer for counters `bits` wide (1..=32) on wheels `wheel`,
    /// with no reference yet: the first counts only set it.
    pub fn new(wheel: Wheel<T>, bits: u32) -> Self {
        Self {
            wheel,
            bits,
            last: None,
        }
    }

    /// The same odometer with reference counts `[right, left]` (e.g. a
    /// decoder's counts at the start of a run).
    #[must_use]
    pub fn with_reference(mut self, counts: [u32; 2]) -> Self {
        self.last = Some(counts);
        self
    }

    /// The wheels' encoder.
    pub fn wheel(&self) -> &Wheel<T> {
        &self.wheel
    }

    /// The wheel travels (m) since the last counts `[right, left]`, or
    /// `None` for the first counts (they become the reference). A count
    /// difference is the shortest way round the counter (`wrapping_diff`),
    /// so a counter that wraps between two readings costs nothing.
    pub fn travel(&mut self, counts: [u32; 2]) -> Option<WheelTravel<T>> {
        let travel = self.travel_since(counts);
        self.last = Some(counts);
        travel
    }

    /// The wheel travels (m) from the reference counts to `counts`, leaving
    /// the reference where it is (`None` before the first counts): what a
    /// caller checks before it accepts the counts.
    pub fn travel_since(&self, counts: [u32; 2]) -> Option<WheelTravel<T>> {
        let last = self.last?;
        Some(WheelTravel {
            d1: self
                .wheel
                .distance(wrapping_diff(counts[0], last[0], self.bits)),
            d2: self
                .wheel
                .distance(wrapping_diff(counts[1], last[1], self.bits)),
        })
    }

    /// Makes `counts` the reference, discarding whatever the wheels did
    /// since the last counts (a link that lost track of the counts).
    pub fn set_reference(&mut self, counts: [u32; 2]) {
        self.last = Some(counts);
    }
}

/// IR pair readings -> an observation of the wall they see.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IrAssociation<T> {
    /// The pair's mounting.
    pub pair: IrPair<T>,
    /// Largest estimated pair-to-wall distance accepted (m).
    pub range: T,
    /// `R11 = var(e_ds1)`, m^2.
    pub r11: T,
    /// `R22 = var(e_ds2)`, m^2.
    pub r22: T,
}

impl<T: Scalar> IrAssociation<T> {
    /// The observation of the readings `[d_s1, d_s2]` (m) at the estimate
    /// `x` (`[x, y, theta]`): the axis-aligned wall of `walls` that the
    /// pair's sensing ray hits within [`IrAssociation::range`], or `None`
    /// (no such wall: the reading is dropped).
    pub fn observe(
        &self,
        x: &locus_core::nalgebra::Vector3<T>,
        walls: &[Segment<T>],
        [ds1, ds2]: [T; 2],
    ) -> Option<IrPairObservation<T>> {
        let wall = associate_ir_wall(x, &self.pair, walls, self.range)?;
        Some(IrPairObservation {
            pair: self.pair,
            wall,
            ds1,
            ds2,
            r11: self.r11,
            r22: self.r22,
        })
    }
}

/// What paper 001's localiser needs to know of the robot and the filter
/// (SI units; variances per filter step). The simulator's `SquareConfig`
/// and the robot-link host build their [`Localiser`] from it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocaliserConfig<T> {
    /// Distance between the wheels `b`, m.
    pub wheelbase: T,
    /// Wheel radius `R`, m.
    pub wheel_radius: T,
    /// Encoder lines per shaft revolution `N` (x4 decoding).
    pub encoder_lines: u32,
    /// Encoder-shaft revolutions per wheel revolution `G`.
    pub encoder_gear: T,
    /// Width of the encoder counters the localiser receives, bits (20 for
    /// paper 004's decoder, 32 on the robot link).
    pub counter_bits: u32,
    /// IR pair spacing `L`, m (pair centred on the robot).
    pub ir_spacing: T,
    /// Largest pair-to-wall distance accepted by the association, m.
    pub association_range: T,
    /// `Q11 = var(e_d)`, m^2 per step.
    pub q11: T,
    /// `Q22 = var(e_dtheta)`, rad^2 per step.
    pub q22: T,
    /// `R11 = var(e_ds1)`, m^2.
    pub r11: T,
    /// `R22 = var(e_ds2)`, m^2.
    pub r22: T,
    /// Chi-square gate confidence in (0, 1), or `None` for no gate.
    pub gate_confidence: Option<f64>,
    /// Initial estimate `[x, y, theta]`, m, m, rad.
    pub start: [T; 3],
    /// Standard deviations of the initial estimate, m, m, rad.
    pub initial_std: [T; 3],
}

impl<T: Real> LocaliserConfig<T> {
    /// `Ok(())` if every value is in its domain.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<(), Error> {
        let pos = |v: T| v.is_finite() && v > T::zero();
        let checks = [
            (
                [
                    self.wheelbase,
                    self.wheel_radius,
                    self.encoder_gear,
                    self.ir_spacing,
                ]
                .into_iter()
                .all(pos)
                    && self.encoder_lines > 0,
                "localiser geometry (wheelbase, wheel_radius, encoder_lines, encoder_gear, ir_spacing) must be finite and > 0",
            ),
            (
                (1..=32).contains(&self.counter_bits),
                "localiser counter_bits must be in 1..=32",
            ),
            (
                [
                    self.association_range,
                    self.q11,
                    self.q22,
                    self.r11,
                    self.r22,
                ]
                .into_iter()
                .all(pos),
                "localiser association_range, q11, q22, r11, r22 must be finite and > 0",
            ),
            (
                self.start.iter().all(|v| v.is_finite()) && self.initial_std.into_iter().all(pos),
                "localiser start must be finite and initial_std finite and > 0",
            ),
            (
                self.gate_confidence.is_none_or(|c| c > 0.0 && c < 1.0),
                "localiser gate_confidence must be in (0, 1)",
            ),
        ];
        match checks.into_iter().find(|(ok, _)| !ok) {
            Some((_, what)) => Err(Error::InvalidParameter(what)),
            None => Ok(()),
        }
    }

    /// The localiser of this configuration, at its initial belief
    /// `N(start, diag(initial_std^2))`, Joseph form, with the gate.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first bad field
    /// ([`LocaliserConfig::validate`]).
    pub fn localiser(&self) -> Result<Localiser<T>, Error> {
        self.validate()?;
        let mut ekf = Ekf::<T>::default();
        if let Some(c) = self.gate_confidence {
            ekf = ekf.with_gate(locus_core::ChiSquareGate::new(c)?);
        }
        let [s0, s1, s2] = self.start;
        let [d0, d1, d2] = self.initial_std;
        let belief = locus_core::Belief::new(
            locus_core::nalgebra::Vector3::new(s0, s1, s2),
            locus_core::nalgebra::Matrix3::from_diagonal(&locus_core::nalgebra::Vector3::new(
                d0 * d0,
                d1 * d1,
                d2 * d2,
            )),
        );
        Ok(Localiser::new(
            ekf,
            belief,
            DiffDrive::new(self.wheelbase, self.q11, self.q22),
            Odometer::new(
                Wheel::new(self.encoder_lines, self.encoder_gear, self.wheel_radius),
                self.counter_bits,
            ),
            IrAssociation {
                pair: IrPair::centred(self.ir_spacing),
                range: self.association_range,
                r11: self.r11,
                r22: self.r22,
            },
        ))
    }
}

/// What an IR reading did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum IrOutcome<T: Scalar> {
    /// No wall in range along the sensing ray: dropped.
    Unassociated,
    /// Associated: the observation and what the filter did with it.
    Associated {
        /// The observation (wall, readings, `R`).
        observation: IrPairObservation<T>,
        /// Applied (NIS, `S`, gain), gated, or no measurement.
        update: Update<T, 3, 2>,
    },
}

impl<T: Scalar> IrOutcome<T> {
    /// Whether the reading corrected the belief.
    pub fn applied(&self) -> bool {
        matches!(self, IrOutcome::Associated { update, .. } if update.applied())
    }
}

/// Paper 001's running localiser: the running filter, the drive model, the
/// odometer and the IR association.
#[derive(Debug, Clone)]
pub struct Localiser<T: Scalar> {
    /// The running filter (belief, gate, consistency monitor).
    pub filter: RunningFilter<T, 3>,
    /// The differential-drive model (wheelbase, `Q`).
    pub model: DiffDrive<T>,
    /// Counts -> wheel travels.
    pub odometer: Odometer<T>,
    /// Readings -> observations.
    pub ir: IrAssociation<T>,
}

impl<T: Real> Localiser<T> {
    /// A localiser starting from `belief`.
    pub fn new(
        ekf: Ekf<T>,
        belief: locus_core::Belief<T, 3>,
        model: DiffDrive<T>,
        odometer: Odometer<T>,
        ir: IrAssociation<T>,
    ) -> Self {
        Self {
            filter: RunningFilter::start(Rules::new(ekf), belief, ()),
            model,
            odometer,
            ir,
        }
    }

    /// The same localiser with a gate recovery policy.
    #[must_use]
    pub fn with_recovery(mut self, recovery: Recovery<T>) -> Self {
        let rules = self.filter.rules().with_recovery(recovery);
        self.filter.set_rules(rules);
        self
    }

    /// The odometer (its reference counts and wheels).
    pub fn odometer(&self) -> &Odometer<T> {
        &self.odometer
    }

    /// Makes `counts` the odometer's reference without predicting: the
    /// travel since the last counts is unknown (see
    /// [`Odometer::set_reference`]).
    pub fn set_reference_counts(&mut self, counts: [u32; 2]) {
        self.odometer.set_reference(counts);
    }

    /// The belief now.
    pub fn belief(&self) -> &locus_core::Belief<T, 3> {
        self.filter.belief()
    }

    /// Prediction with the wheel travels `u` (eq. 7-13).
    ///
    /// # Errors
    /// As [`Ekf::predict`]; the belief is then unchanged.
    #[inline(always)]
    pub fn predict(&mut self, u: &WheelTravel<T>) -> Result<(), Error> {
        self.filter.predict(&self.model, u)
    }

    /// New encoder counts `[right, left]`: the wheel travels since the last
    /// ones, predicted in `parts` equal steps (the robot link predicts
    /// through lost packets this way; 1 otherwise). `Ok(None)` for the
    /// first counts, which only set the odometer's reference.
    ///
    /// # Errors
    /// As [`Ekf::predict`]; the belief is then unchanged (a failure on a
    /// later part keeps the earlier parts' prediction).
    pub fn counts(
        &mut self,
        counts: [u32; 2],
        parts: u32,
    ) -> Result<Option<WheelTravel<T>>, Error> {
        let Some(total) = self.odometer.travel(counts) else {
            return Ok(None);
        };
        let n: T = locus_core::cast(f64::from(parts.max(1)));
        let u = if parts > 1 {
            WheelTravel {
                d1: total.d1 / n,
                d2: total.d2 / n,
            }
        } else {
            total
        };
        for _ in 0..parts.max(1) {
            self.predict(&u)?;
        }
        Ok(Some(total))
    }

    /// An IR reading `[d_s1, d_s2]` (m) of the walls `walls`: associated on
    /// the current (predicted) estimate, then the correction behind the
    /// gate.
    ///
    /// # Errors
    /// As [`Ekf::correct`]; the belief is then unchanged.
    #[inline]
    pub fn ir(&mut self, walls: &[Segment<T>], readings: [T; 2]) -> Result<IrOutcome<T>, Error> {
        let Some(observation) = self.ir.observe(&self.filter.belief().x, walls, readings) else {
            return Ok(IrOutcome::Unassociated);
        };
        let update = self.filter.correct(&observation, &observation.z())?;
        Ok(IrOutcome::Associated {
            observation,
            update,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_wrap_and_split() {
        let wheel = Wheel::new(90, 1.0, 0.028);
        let mut o = Odometer::<f64>::new(wheel, 20);
        assert_eq!(o.travel([5, 7]), None);
        // The 20-bit counter wraps: 3 -> (2^20 - 2) is 5 counts back.
        let mut o = Odometer::<f64>::new(wheel, 20).with_reference([(1 << 20) - 2, 3]);
        let u = o.travel([3, (1 << 20) - 2]).unwrap();
        assert_eq!(u.d1, wheel.distance(5));
        assert_eq!(u.d2, wheel.distance(-5));
        // 32-bit link counters: the same through u32 wrapping.
        let mut o = Odometer::<f64>::new(wheel, 32).with_reference([u32::MAX, 0]);
        let u = o.travel([1, u32::MAX]).unwrap();
        assert_eq!((u.d1, u.d2), (wheel.distance(2), wheel.distance(-1)));
    }
}
