//! What a telemetry packet may say: limits that its content must respect
//! before the host lets it touch the filter (`docs/protocol.md`, "Plausibility").
//!
//! A packet can pass the CRC and still be impossible: a bit flip the CRC
//! missed, a forged packet, a robot whose encoder counter was reset. Such a
//! packet is refused whole and counted; because the encoder counts are
//! cumulative, the next plausible packet's difference still covers the
//! travel, so a refused packet loses nothing.

use crate::Error;

/// The limits a telemetry packet's content must respect, measured from the
/// last accepted packet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Top wheel speed of the robot (m/s): a wheel travel longer than this
    /// speed times the elapsed robot time (plus two count quanta of
    /// rounding) is impossible. Default 1 m/s.
    pub max_wheel_speed: f64,
    /// Longest robot time one packet may cover (s): the robot time since the
    /// last accepted packet must be positive and at most this times the
    /// number of packets it stands for (the skipped ones plus itself), so
    /// that a time stamp cannot make any travel look plausible. Default 1 s.
    pub max_period: f64,
    /// Longest distance sensor reading (m): an IR reading must lie in
    /// `[0, max_ir_range]`. Default 4 m.
    pub max_ir_range: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_wheel_speed: 1.0,
            max_period: 1.0,
            max_ir_range: 4.0,
        }
    }
}

/// Why a packet was refused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Implausible {
    /// The robot time did not advance since the last accepted packet (s).
    TimeNotAdvancing {
        /// Robot time since the last accepted packet (s, <= 0).
        elapsed: f64,
    },
    /// The robot time advanced more than the packets can cover (s).
    TimeGap {
        /// Robot time since the last accepted packet (s).
        elapsed: f64,
        /// Largest plausible: packets times `max_period` (s).
        limit: f64,
    },
    /// A wheel travelled further than the top speed allows (m).
    Travel {
        /// 0 right, 1 left.
        wheel: usize,
        /// The travel the counts say (m).
        travel: f64,
        /// Largest plausible travel (m).
        limit: f64,
    },
    /// An IR reading outside `[0, max_ir_range]` (m).
    IrReading {
        /// The reading (m).
        value: f64,
    },
}

impl Limits {
    /// Checks that every limit is finite and > 0.
    ///
    /// # Errors
    /// [`Error::Config`] naming the limit.
    pub fn validate(&self) -> Result<(), Error> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.max_wheel_speed) {
            return Err(Error::Config(
                "limits.max_wheel_speed must be finite and > 0 m/s",
            ));
        }
        if !pos(self.max_period) {
            return Err(Error::Config("limits.max_period must be finite and > 0 s"));
        }
        if !pos(self.max_ir_range) {
            return Err(Error::Config(
                "limits.max_ir_range must be finite and > 0 m",
            ));
        }
        Ok(())
    }

    /// Checks a packet against the last accepted one: `elapsed` robot
    /// seconds, standing for `packets` packets (skipped ones plus itself),
    /// wheel travels `travel` `[right, left]` (m) with count quantum
    /// `quantum` (m), and its IR reading.
    ///
    /// # Errors
    /// The first limit the packet breaks.
    pub fn check(
        &self,
        elapsed: f64,
        packets: u32,
        travel: [f64; 2],
        quantum: f64,
        ir: Option<[f32; 2]>,
    ) -> Result<(), Implausible> {
        if elapsed.is_nan() || elapsed <= 0.0 {
            return Err(Implausible::TimeNotAdvancing { elapsed });
        }
        let limit = f64::from(packets.max(1)) * self.max_period;
        if elapsed > limit {
            return Err(Implausible::TimeGap { elapsed, limit });
        }
        let limit = self.max_wheel_speed * elapsed + 2.0 * quantum;
        for (wheel, travel) in travel.into_iter().enumerate() {
            if travel.is_nan() || travel.abs() > limit {
                return Err(Implausible::Travel {
                    wheel,
                    travel,
                    limit,
                });
            }
        }
        for value in ir.into_iter().flatten().map(f64::from) {
            if !(0.0..=self.max_ir_range).contains(&value) {
                return Err(Implausible::IrReading { value });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_limit_refuses_what_breaks_it() {
        let l = Limits::default();
        let q = 0.001;
        assert_eq!(
            l.check(0.01, 1, [0.005, -0.005], q, Some([0.3, 0.4])),
            Ok(())
        );
        // A skipped packet lets the time (and with it the travel) grow.
        assert_eq!(l.check(1.5, 2, [1.4, 1.4], q, None), Ok(()));
        assert!(matches!(
            l.check(0.0, 1, [0.0, 0.0], q, None),
            Err(Implausible::TimeNotAdvancing { .. })
        ));
        assert!(matches!(
            l.check(1.5, 1, [0.0, 0.0], q, None),
            Err(Implausible::TimeGap { .. })
        ));
        assert!(matches!(
            l.check(0.01, 1, [0.0, 0.05], q, None),
            Err(Implausible::Travel { wheel: 1, .. })
        ));
        assert!(matches!(
            l.check(0.01, 1, [0.0, 0.0], q, Some([0.3, -0.1])),
            Err(Implausible::IrReading { .. })
        ));
        assert!(matches!(
            l.check(0.01, 1, [0.0, 0.0], q, Some([1e30, 0.1])),
            Err(Implausible::IrReading { .. })
        ));
    }

    #[test]
    fn limits_must_be_finite_and_positive() {
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            for i in 0..3 {
                let mut l = Limits::default();
                *[
                    &mut l.max_wheel_speed,
                    &mut l.max_period,
                    &mut l.max_ir_range,
                ][i] = bad;
                assert!(l.validate().is_err(), "{i} {bad}");
            }
        }
        assert!(Limits::default().validate().is_ok());
    }
}
