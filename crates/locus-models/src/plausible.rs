//! What a small wheeled robot's records may say: the limits a value must
//! respect before it touches a filter, one set of rules for the robot link
//! (a telemetry packet, `docs/protocol.md`, "Plausibility") and the replay
//! of a recorded log (an odometry record, a map, a sensor mount, a noise
//! level; `docs/log-format.md`).
//!
//! A value can be finite, well-formed and still impossible: a bit flip a
//! CRC missed, an encoder counter reset, a typo of `1e6` for `1.0` in a
//! log. One such value would put the estimate kilometres off (a speed) or
//! make the covariance overflow (a noise of `1e308`). What breaks a limit
//! is refused whole and counted, never clamped: a clamped speed is as wrong
//! as the original, only less visibly.

/// The limits, each > 0 and finite ([`Limits::validate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Top speed of the robot and of either wheel, m/s: a logged forward
    /// speed above it, or a wheel travel longer than it times the elapsed
    /// time (plus two count quanta of rounding), is impossible.
    pub max_speed: f64,
    /// Top turn rate of the robot, rad/s.
    pub max_turn_rate: f64,
    /// Longest time one telemetry packet may cover, s: the robot time since
    /// the last accepted packet must be positive and at most this times the
    /// number of packets it stands for (the skipped ones plus itself), so
    /// that a time stamp cannot make any travel look plausible.
    pub max_period: f64,
    /// Longest time between two odometry records of a log, s: a record
    /// further than this after the one listed before it is refused (a time
    /// stamp of `1e308` would make the prediction over the gap overflow).
    pub max_odometry_gap: f64,
    /// Longest distance-sensor (IR) reading of a packet, m: a reading must
    /// lie in `[0, max_ir_range]`.
    pub max_ir_range: f64,
    /// Largest coordinate of a map, a start pose or a ground truth, m (its
    /// absolute value): a small robot's world is far smaller, and squares
    /// of larger values lose every digit a position needs.
    pub max_coordinate: f64,
    /// Largest distance of a sensor from the robot's centre, m.
    pub max_mount_offset: f64,
}

impl Limits {
    /// Generic limits for any small wheeled robot (the replay's default):
    /// 10 m/s, 4 pi rad/s (two turns a second), a 1 s packet period, 60 s
    /// between odometry records, a 4 m IR reading, coordinates within
    /// 100 km, a sensor within 10 m of the centre. A robot beyond them
    /// (a racing car) states its own.
    pub const GENERIC: Self = Self {
        max_speed: 10.0,
        max_turn_rate: 4.0 * core::f64::consts::PI,
        max_period: 1.0,
        max_odometry_gap: 60.0,
        max_ir_range: 4.0,
        max_coordinate: 1e5,
        max_mount_offset: 10.0,
    };

    /// Paper 001's robot (the link host's default): wheels at 1 m/s at
    /// most, IR sensors reading up to 4 m; the rest as [`Limits::GENERIC`].
    pub const PAPER_001: Self = Self {
        max_speed: 1.0,
        ..Self::GENERIC
    };

    /// Checks that every limit is finite and > 0.
    ///
    /// # Errors
    /// The limit that is not, as a message naming it and its unit.
    pub fn validate(&self) -> Result<(), &'static str> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        for (v, what) in [
            (
                self.max_speed,
                "limits.max_speed must be finite and > 0 m/s",
            ),
            (
                self.max_turn_rate,
                "limits.max_turn_rate must be finite and > 0 rad/s",
            ),
            (
                self.max_period,
                "limits.max_period must be finite and > 0 s",
            ),
            (
                self.max_odometry_gap,
                "limits.max_odometry_gap must be finite and > 0 s",
            ),
            (
                self.max_ir_range,
                "limits.max_ir_range must be finite and > 0 m",
            ),
            (
                self.max_coordinate,
                "limits.max_coordinate must be finite and > 0 m",
            ),
            (
                self.max_mount_offset,
                "limits.max_mount_offset must be finite and > 0 m",
            ),
        ] {
            if !pos(v) {
                return Err(what);
            }
        }
        Ok(())
    }

    /// Checks a telemetry packet against the last accepted one: `elapsed`
    /// robot seconds, standing for `packets` packets (skipped ones plus
    /// itself), wheel travels `travel` `[right, left]` (m) with count
    /// quantum `quantum` (m), and its IR reading.
    ///
    /// # Errors
    /// The first limit the packet breaks.
    pub fn check_packet(
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
        let limit = self.max_speed * elapsed + 2.0 * quantum;
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

    /// Checks an odometry record of a log: its forward speed `v` (m/s) and
    /// turn rate `omega` (rad/s), and its time `gap` (s) after the record
    /// listed before it (`None` for the first).
    ///
    /// # Errors
    /// The first limit the record breaks.
    pub fn check_odometry(&self, v: f64, omega: f64, gap: Option<f64>) -> Result<(), Implausible> {
        if v.is_nan() || v.abs() > self.max_speed {
            return Err(Implausible::Speed {
                value: v,
                limit: self.max_speed,
            });
        }
        if omega.is_nan() || omega.abs() > self.max_turn_rate {
            return Err(Implausible::TurnRate {
                value: omega,
                limit: self.max_turn_rate,
            });
        }
        if let Some(gap) = gap
            && (gap.is_nan() || gap > self.max_odometry_gap)
        {
            return Err(Implausible::OdometryGap {
                gap,
                limit: self.max_odometry_gap,
            });
        }
        Ok(())
    }

    /// Checks a coordinate (m) of a map, a start pose or a ground truth.
    ///
    /// # Errors
    /// [`Implausible::Coordinate`] if its absolute value is above
    /// [`Limits::max_coordinate`] (or it is NaN).
    pub fn check_coordinate(&self, value: f64) -> Result<(), Implausible> {
        if value.is_nan() || value.abs() > self.max_coordinate {
            return Err(Implausible::Coordinate {
                value,
                limit: self.max_coordinate,
            });
        }
        Ok(())
    }

    /// Checks a sensor mount: its offset `(x, y)` from the robot's centre
    /// (m) and its yaw (rad, within one turn either way).
    ///
    /// # Errors
    /// [`Implausible::MountOffset`] or [`Implausible::MountYaw`].
    pub fn check_mount(&self, x: f64, y: f64, yaw: f64) -> Result<(), Implausible> {
        let offset = libm::hypot(x, y);
        if offset.is_nan() || offset > self.max_mount_offset {
            return Err(Implausible::MountOffset {
                value: offset,
                limit: self.max_mount_offset,
            });
        }
        if yaw.is_nan() || yaw.abs() > core::f64::consts::TAU {
            return Err(Implausible::MountYaw { value: yaw });
        }
        Ok(())
    }

    /// The largest plausible value of a noise level, by its name in a
    /// `noise` record (`None` for an unknown name): a process noise whose
    /// one-second standard deviation reaches the top speed or turn rate
    /// (`q_v <= max_speed^2` m^2/s, `q_omega <= max_turn_rate^2` rad^2/s),
    /// a range noise of the size of the world (`max_coordinate` m), a
    /// bearing noise of half a turn (pi rad).
    #[must_use]
    pub fn max_noise(&self, name: &str) -> Option<f64> {
        Some(match name {
            "q_v" => self.max_speed * self.max_speed,
            "q_omega" => self.max_turn_rate * self.max_turn_rate,
            "sigma_range" => self.max_coordinate,
            "sigma_bearing" => core::f64::consts::PI,
            _ => return None,
        })
    }
}

impl Default for Limits {
    /// [`Limits::GENERIC`].
    fn default() -> Self {
        Self::GENERIC
    }
}

/// Why a value was refused.
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
    /// A forward speed above the top speed (m/s).
    Speed {
        /// The speed, m/s.
        value: f64,
        /// The top speed, m/s.
        limit: f64,
    },
    /// A turn rate above the top turn rate (rad/s).
    TurnRate {
        /// The turn rate, rad/s.
        value: f64,
        /// The top turn rate, rad/s.
        limit: f64,
    },
    /// An odometry record too long after the one before it (s).
    OdometryGap {
        /// The time since the record listed before it, s.
        gap: f64,
        /// The longest plausible, s.
        limit: f64,
    },
    /// A coordinate beyond the world's size (m).
    Coordinate {
        /// The coordinate, m.
        value: f64,
        /// The largest plausible absolute value, m.
        limit: f64,
    },
    /// A sensor too far from the robot's centre (m).
    MountOffset {
        /// Its distance from the centre, m.
        value: f64,
        /// The largest plausible, m.
        limit: f64,
    },
    /// A sensor yaw beyond one turn either way (rad).
    MountYaw {
        /// The yaw, rad.
        value: f64,
    },
    /// A noise level above its largest plausible value
    /// ([`Limits::max_noise`]).
    Noise {
        /// The level, in its unit.
        value: f64,
        /// The largest plausible, in its unit.
        limit: f64,
    },
}

/// A value for a message: in full when short, else in scientific notation
/// (a `1e308` is not printed as 309 digits).
struct Short(f64);

impl core::fmt::Display for Short {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let v = self.0;
        if v != 0.0 && (v.abs() >= 1e6 || v.abs() < 1e-4) {
            write!(f, "{v:e}")
        } else {
            write!(f, "{v}")
        }
    }
}

impl core::fmt::Display for Implausible {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::TimeNotAdvancing { elapsed } => write!(
                f,
                "the robot time did not advance ({} s since the last accepted packet)",
                Short(elapsed)
            ),
            Self::TimeGap { elapsed, limit } => write!(
                f,
                "the robot time jumped {} s, more than the {} s its packets can cover",
                Short(elapsed),
                Short(limit)
            ),
            Self::Travel {
                wheel,
                travel,
                limit,
            } => write!(
                f,
                "the {} wheel travelled {} m, more than the {} m its top speed allows",
                if wheel == 0 { "right" } else { "left" },
                Short(travel),
                Short(limit)
            ),
            Self::IrReading { value } => write!(f, "an IR reading of {} m", Short(value)),
            Self::Speed { value, limit } => write!(
                f,
                "speed {} m/s is above the top speed, {} m/s",
                Short(value),
                Short(limit)
            ),
            Self::TurnRate { value, limit } => write!(
                f,
                "turn rate {} rad/s is above the top turn rate, {} rad/s",
                Short(value),
                Short(limit)
            ),
            Self::OdometryGap { gap, limit } => write!(
                f,
                "{} s after the record before it, more than {} s",
                Short(gap),
                Short(limit)
            ),
            Self::Coordinate { value, limit } => write!(
                f,
                "coordinate {} m is beyond +-{} m",
                Short(value),
                Short(limit)
            ),
            Self::MountOffset { value, limit } => write!(
                f,
                "the sensor is {} m from the robot's centre, more than {} m",
                Short(value),
                Short(limit)
            ),
            Self::MountYaw { value } => write!(
                f,
                "the sensor's yaw {} rad is beyond one turn either way",
                Short(value)
            ),
            Self::Noise { value, limit } => write!(
                f,
                "{} is above the largest plausible value, {}",
                Short(value),
                Short(limit)
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_packet_limit_refuses_what_breaks_it() {
        let l = Limits::PAPER_001;
        let q = 0.001;
        assert_eq!(
            l.check_packet(0.01, 1, [0.005, -0.005], q, Some([0.3, 0.4])),
            Ok(())
        );
        // A skipped packet lets the time (and with it the travel) grow.
        assert_eq!(l.check_packet(1.5, 2, [1.4, 1.4], q, None), Ok(()));
        assert!(matches!(
            l.check_packet(0.0, 1, [0.0, 0.0], q, None),
            Err(Implausible::TimeNotAdvancing { .. })
        ));
        assert!(matches!(
            l.check_packet(1.5, 1, [0.0, 0.0], q, None),
            Err(Implausible::TimeGap { .. })
        ));
        assert!(matches!(
            l.check_packet(0.01, 1, [0.0, 0.05], q, None),
            Err(Implausible::Travel { wheel: 1, .. })
        ));
        assert!(matches!(
            l.check_packet(0.01, 1, [0.0, 0.0], q, Some([0.3, -0.1])),
            Err(Implausible::IrReading { .. })
        ));
        assert!(matches!(
            l.check_packet(0.01, 1, [0.0, 0.0], q, Some([1e30, 0.1])),
            Err(Implausible::IrReading { .. })
        ));
    }

    #[test]
    fn each_record_limit_refuses_what_breaks_it() {
        let l = Limits::GENERIC;
        assert_eq!(l.check_odometry(0.5, -1.0, Some(0.1)), Ok(()));
        assert!(matches!(
            l.check_odometry(1e6, 0.0, None),
            Err(Implausible::Speed { .. })
        ));
        assert!(matches!(
            l.check_odometry(0.0, f64::NAN, None),
            Err(Implausible::TurnRate { .. })
        ));
        assert!(matches!(
            l.check_odometry(0.0, 0.0, Some(1e308)),
            Err(Implausible::OdometryGap { .. })
        ));
        assert!(l.check_coordinate(-99_999.0).is_ok());
        assert!(l.check_coordinate(1e308).is_err());
        assert!(l.check_mount(0.2, 0.0, 0.08).is_ok());
        assert!(l.check_mount(1e308, 0.0, 0.0).is_err());
        assert!(l.check_mount(0.0, 0.0, 1e308).is_err());
        assert_eq!(l.max_noise("q_v"), Some(100.0));
        assert_eq!(l.max_noise("nope"), None);
    }

    #[test]
    fn limits_must_be_finite_and_positive() {
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            for i in 0..7 {
                let mut l = Limits::default();
                *[
                    &mut l.max_speed,
                    &mut l.max_turn_rate,
                    &mut l.max_period,
                    &mut l.max_odometry_gap,
                    &mut l.max_ir_range,
                    &mut l.max_coordinate,
                    &mut l.max_mount_offset,
                ][i] = bad;
                assert!(l.validate().is_err(), "{i} {bad}");
            }
        }
        assert!(Limits::default().validate().is_ok());
        assert!(Limits::PAPER_001.validate().is_ok());
    }

    #[test]
    fn huge_values_print_short() {
        extern crate std;
        let s = std::format!(
            "{}",
            Implausible::Speed {
                value: 1e308,
                limit: 10.0,
            }
        );
        assert!(s.contains("1e308") && s.len() < 80, "{s}");
    }
}
