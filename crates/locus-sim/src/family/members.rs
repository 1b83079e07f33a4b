//! The family's members ([`Member::family`]).

use core::f64::consts::PI;

use super::{Correlated, Member, Odometry, OdometrySource, Sensor, SensorKind};

/// A range-bearing sensor with white noise, at the robot's centre, along
/// its heading, no outliers.
const fn range_bearing(
    rate: f64,
    sigma_range: f64,
    sigma_bearing: f64,
    max_range: f64,
    half_fov: f64,
    in_view: f64,
) -> Sensor {
    Sensor {
        kind: SensorKind::RangeBearing,
        rate,
        sigma_range,
        sigma_bearing,
        correlated: None,
        outliers: 0.0,
        mount_x: 0.0,
        yaw: 0.0,
        max_range,
        half_fov,
        in_view,
    }
}

/// Wheel odometry without calibration errors.
const fn wheels(rate: f64, track: f64, sigma_wheel: f64) -> Odometry {
    Odometry {
        source: OdometrySource::Wheels { track, sigma_wheel },
        rate,
        v_scale: 1.0,
        omega_scale: 1.0,
        omega_bias: 0.0,
    }
}

/// Commanded velocities without calibration errors.
const fn commanded(rate: f64, lag: f64, sigma_v: f64, sigma_omega: f64) -> Odometry {
    Odometry {
        source: OdometrySource::Commanded {
            lag,
            sigma_v,
            sigma_omega,
        },
        rate,
        v_scale: 1.0,
        omega_scale: 1.0,
        omega_bias: 0.0,
    }
}

/// A member driving in a 4 m disc at 0.1-0.5 m/s, up to 1 rad/s, truth
/// at 50 Hz without an offset.
const fn member(
    name: &'static str,
    about: &'static str,
    duration: f64,
    seed: u64,
    sensor: Sensor,
    odometry: Odometry,
) -> Member {
    Member {
        name,
        about,
        duration,
        seed,
        area_radius: 4.0,
        speed: (0.1, 0.5),
        max_turn_rate: 1.0,
        sensor,
        odometry,
        truth_rate: 50.0,
        truth_heading_offset: 0.0,
        needs_v3: false,
    }
}

impl Member {
    /// The family: eleven robots spanning sensor rates 1-30 Hz, range
    /// noise 0.01-0.5 m, bearing noise 0.002-0.05 rad, errors correlated
    /// over 0.5-3 s, range-only beacons, wheel odometry at 10-100 Hz and
    /// commanded velocities with a lag, scale errors up to 8 %, turn-rate
    /// biases, 1-10 landmarks in view, 5 % outliers, sensors off-centre
    /// and off-axis, truth heading offsets. Durations 120-600 s.
    #[must_use]
    #[allow(clippy::too_many_lines)]
    pub fn family() -> Vec<Self> {
        vec![
            Self {
                truth_heading_offset: -0.08,
                ..member(
                    "laser-5hz-offset",
                    "2-D laser 0.2 m ahead, 0.08 rad off-axis, 230 deg field of view; \
                     wheel odometry 10 Hz, 3-4 % scale errors; truth heading offset -0.08 rad",
                    300.0,
                    1,
                    Sensor {
                        mount_x: 0.2,
                        yaw: 0.08,
                        ..range_bearing(5.0, 0.03, 0.026, 8.0, 2.0, 6.0)
                    },
                    Odometry {
                        v_scale: 1.03,
                        omega_scale: 0.96,
                        omega_bias: 0.01,
                        ..wheels(10.0, 0.35, 0.03)
                    },
                )
            },
            member(
                "camera-correlated",
                "MRCLAM-like camera, 60 deg: range errors persisting ~3 s (0.25 m) over 0.05 m \
                 white; commanded velocities 50 Hz, 0.1 s lag, 5 % scale errors",
                600.0,
                2,
                Sensor {
                    correlated: Some(Correlated {
                        tau: 3.0,
                        sigma_range: 0.25,
                        sigma_bearing: 0.002,
                    }),
                    ..range_bearing(8.0, 0.05, 0.008, 6.0, 0.5, 3.0)
                },
                Odometry {
                    v_scale: 1.05,
                    omega_scale: 0.95,
                    ..commanded(50.0, 0.1, 0.08, 0.15)
                },
            ),
            Self {
                speed: (0.1, 0.3),
                ..member(
                    "sonar-slow-1hz",
                    "sonar at 1 Hz, 40 deg beam (bearing 0.05 rad), 2 in view; wheels 20 Hz",
                    600.0,
                    3,
                    range_bearing(1.0, 0.05, 0.05, 5.0, 0.35, 2.0),
                    wheels(20.0, 0.25, 0.02),
                )
            },
            member(
                "precise-30hz",
                "precise scanner 30 Hz (0.01 m, 0.002 rad) 0.1 m ahead, 0.02 rad off-axis, \
                 8 in view; wheels 50 Hz",
                120.0,
                4,
                Sensor {
                    mount_x: 0.1,
                    yaw: 0.02,
                    ..range_bearing(30.0, 0.01, 0.002, 10.0, 1.5, 8.0)
                },
                wheels(50.0, 0.4, 0.005),
            ),
            member(
                "noisy-wheels-100hz",
                "noisy wheels 100 Hz (0.2 m/s each), 8 % scale errors, turn-rate bias -0.02 rad/s; \
                 360 deg sensor 10 Hz",
                300.0,
                5,
                range_bearing(10.0, 0.1, 0.01, 6.0, PI, 5.0),
                Odometry {
                    v_scale: 0.92,
                    omega_scale: 1.08,
                    omega_bias: -0.02,
                    ..wheels(100.0, 0.3, 0.2)
                },
            ),
            Self {
                area_radius: 5.0,
                needs_v3: true,
                ..member(
                    "uwb-beacons",
                    "range-only UWB beacons 10 Hz (0.1 m), 4 in range (v3 range records); \
                     wheels 20 Hz",
                    300.0,
                    6,
                    Sensor {
                        kind: SensorKind::RangeOnly,
                        sigma_bearing: 0.0,
                        ..range_bearing(10.0, 0.1, 0.0, 15.0, PI, 4.0)
                    },
                    wheels(20.0, 0.3, 0.02),
                )
            },
            member(
                "one-landmark",
                "one landmark in view on average, 5 Hz, 70 deg; wheels 20 Hz",
                300.0,
                7,
                range_bearing(5.0, 0.05, 0.01, 5.0, 0.6, 1.0),
                wheels(20.0, 0.3, 0.01),
            ),
            member(
                "outliers-5pct",
                "5 % gross outliers, 10 Hz, 5 in view; commanded velocities 20 Hz",
                300.0,
                8,
                Sensor {
                    outliers: 0.05,
                    ..range_bearing(10.0, 0.05, 0.01, 8.0, 1.2, 5.0)
                },
                commanded(20.0, 0.0, 0.02, 0.05),
            ),
            member(
                "commanded-lag-0.2s",
                "commanded velocities 30 Hz moving 0.2 s late, scale errors 8 % and 7 %, \
                 turn-rate bias 0.03 rad/s; sensor 5 Hz",
                300.0,
                9,
                range_bearing(5.0, 0.2, 0.02, 8.0, 1.0, 4.0),
                Odometry {
                    v_scale: 1.08,
                    omega_scale: 0.93,
                    omega_bias: 0.03,
                    ..commanded(30.0, 0.2, 0.03, 0.06)
                },
            ),
            Self {
                truth_heading_offset: 0.05,
                ..member(
                    "wide-range-2hz",
                    "poor ranges (0.5 m), fine bearings (0.005 rad), 2 Hz, 10 in view; \
                     commanded 10 Hz; truth heading offset 0.05 rad",
                    600.0,
                    10,
                    range_bearing(2.0, 0.5, 0.005, 12.0, PI, 10.0),
                    commanded(10.0, 0.0, 0.05, 0.1),
                )
            },
            member(
                "correlated-only-15hz",
                "no white noise: Gauss-Markov errors only (0.05 m, 0.004 rad, 0.5 s), 15 Hz; \
                 wheels 50 Hz",
                300.0,
                11,
                Sensor {
                    correlated: Some(Correlated {
                        tau: 0.5,
                        sigma_range: 0.05,
                        sigma_bearing: 0.004,
                    }),
                    ..range_bearing(15.0, 0.0, 0.0, 8.0, 1.0, 5.0)
                },
                wheels(50.0, 0.3, 0.03),
            ),
        ]
    }
}
