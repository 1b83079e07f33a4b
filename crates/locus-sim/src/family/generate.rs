//! A member's log: the true path, the odometry, the sightings and the
//! truth records, written as Locus CSV text (docs/log-format.md).

use core::f64::consts::PI;
use core::fmt::Write as _;

use locus_core::wrap_angle;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use super::motion::TruePath;
use super::{Member, OdometrySource, SensorKind, Truth};
use crate::noise::gauss;

/// Time of the first odometry record, s (not 0, so that a reader that
/// assumes logs start at 0 shows up).
pub const T0: f64 = 100.0;

/// A generated log with what went into it.
#[derive(Debug, Clone, PartialEq)]
pub struct Generated {
    /// The log in the Locus CSV format (v2; v3 `range` records for a
    /// range-only member).
    pub text: String,
    /// The true noise and calibration.
    pub truth: Truth,
    /// The true trajectory (the `truth` records are its samples, heading
    /// offset by [`Truth::truth_heading_offset`]).
    pub path: TruePath,
    /// The landmarks: id, x (m), y (m).
    pub landmarks: Vec<(u32, f64, f64)>,
    /// Sightings written (including outliers).
    pub sightings: usize,
    /// Scans taken.
    pub scans: usize,
}

impl Generated {
    /// Landmarks sighted per scan on average.
    #[must_use]
    #[allow(clippy::cast_precision_loss)]
    pub fn mean_in_view(&self) -> f64 {
        self.sightings as f64 / self.scans.max(1) as f64
    }
}

/// A time rounded to the microsecond, so that it is written exactly.
fn micro(t: f64) -> f64 {
    (t * 1e6).round() / 1e6
}

/// The log of `member` drawn with `seed`, and its [`Truth`].
#[must_use]
pub fn generate(member: &Member, seed: u64) -> (String, Truth) {
    let g = generate_with(member, seed);
    (g.text, g.truth)
}

/// A member's segment state: velocities and periods left.
struct Segment {
    v: f64,
    omega: f64,
    left: u32,
}

/// The next segment from `pose`: back towards the centre (slow, 0.5 s)
/// beyond 60 % of the area's radius, else a random arc of 1-4 s.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
fn next_segment(member: &Member, pose: [f64; 3], rng: &mut StdRng) -> Segment {
    let (lo, hi) = member.speed;
    let w_max = member.max_turn_rate;
    let rate = member.odometry.rate;
    let draw = |rng: &mut StdRng, a: f64, b: f64| if b > a { rng.random_range(a..b) } else { a };
    let [x, y, th] = pose;
    let (v, omega, length) = if x.hypot(y) > 0.6 * member.area_radius {
        let error = wrap_angle((-y).atan2(-x) - th);
        (lo, (2.0 * error).clamp(-w_max, w_max), 0.5)
    } else {
        (
            draw(rng, lo, hi),
            draw(rng, -w_max, w_max),
            draw(rng, 1.0, 4.0),
        )
    };
    Segment {
        v,
        omega,
        left: ((length * rate).round() as u32).max(1),
    }
}

/// Gauss-Markov state of one landmark: range and bearing errors and the
/// time they hold at.
#[derive(Clone, Copy)]
struct Markov {
    range: f64,
    bearing: f64,
    time: f64,
}

/// As [`generate`], with the true path, the landmarks and counts.
///
/// # Panics
/// A member whose rates or duration are not positive and finite.
#[must_use]
#[allow(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    clippy::cast_precision_loss,
    clippy::too_many_lines
)]
pub fn generate_with(member: &Member, seed: u64) -> Generated {
    let odo = &member.odometry;
    let s = &member.sensor;
    assert!(
        odo.rate > 0.0 && s.rate > 0.0 && member.truth_rate > 0.0 && member.duration > 0.0,
        "rates and duration must be > 0"
    );
    let truth = member.truth();
    let mut rng = StdRng::seed_from_u64(seed);
    let dt = 1.0 / odo.rate;
    let records = (member.duration * odo.rate).round() as usize;
    let t_end = micro(T0 + records as f64 * dt);

    // Landmarks: uniform over a disc wider than the area by the sensor's
    // range, as dense as `in_view` landmarks in the field of view ask
    // (the field of view covers `half_fov R^2` m^2).
    let radius = member.area_radius + s.max_range;
    let density = s.in_view / (s.half_fov * s.max_range * s.max_range);
    let count = ((density * PI * radius * radius).round() as usize).max(s.in_view.ceil() as usize);
    let landmarks: Vec<(u32, f64, f64)> = (0..count)
        .map(|i| {
            let r = radius * rng.random::<f64>().sqrt();
            let a = 2.0 * PI * rng.random::<f64>();
            (i as u32 + 1, r * a.cos(), r * a.sin())
        })
        .collect();

    // The true path and the odometry records.
    let r0 = 0.5 * member.area_radius * rng.random::<f64>().sqrt();
    let a0 = 2.0 * PI * rng.random::<f64>();
    let start = [
        r0 * a0.cos(),
        r0 * a0.sin(),
        wrap_angle(2.0 * PI * rng.random::<f64>()),
    ];
    let lag = truth.odometry_delay;
    let mut path = TruePath::new(start, T0 + lag, dt);
    let mut odometry = Vec::with_capacity(records + 1);
    let mut segment = Segment {
        v: 0.0,
        omega: 0.0,
        left: 0,
    };
    for k in 0..=records {
        if segment.left == 0 {
            segment = next_segment(member, path.end(), &mut rng);
        }
        segment.left -= 1;
        let (v, omega) = (segment.v, segment.omega);
        // The velocities the robot moves at, and those its odometry reads
        // (before the scale errors and the bias).
        let (moved, read) = match odo.source {
            OdometrySource::Wheels { track, sigma_wheel } => {
                let right = v + omega * track / 2.0 + gauss(&mut rng, sigma_wheel);
                let left = v - omega * track / 2.0 + gauss(&mut rng, sigma_wheel);
                ((v, omega), ((right + left) / 2.0, (right - left) / track))
            }
            OdometrySource::Commanded {
                sigma_v,
                sigma_omega,
                ..
            } => {
                let nv = gauss(&mut rng, sigma_v);
                let nw = gauss(&mut rng, sigma_omega);
                ((v + nv, omega + nw), (v, omega))
            }
        };
        path.push(moved.0, moved.1);
        odometry.push((
            micro(T0 + k as f64 * dt),
            read.0 / odo.v_scale,
            (read.1 - odo.omega_bias) / odo.omega_scale,
        ));
    }

    // Sightings: every landmark in range and in the field of view, at
    // each scan.
    let correlated = s.correlated;
    let mut markov: Vec<Markov> = landmarks
        .iter()
        .map(|_| {
            let (sr, sb) = correlated.map_or((0.0, 0.0), |c| (c.sigma_range, c.sigma_bearing));
            Markov {
                range: gauss(&mut rng, sr),
                bearing: gauss(&mut rng, sb),
                time: T0,
            }
        })
        .collect();
    let scan_dt = 1.0 / s.rate;
    let phase = scan_dt * rng.random::<f64>();
    let mut lines = String::new();
    let (mut sightings, mut scans) = (0, 0);
    for j in 0.. {
        let t = micro(T0 + phase + j as f64 * scan_dt);
        if t > t_end {
            break;
        }
        scans += 1;
        let [x, y, th] = path.pose_at(t);
        let (sx, sy) = (x + s.mount_x * th.cos(), y + s.mount_x * th.sin());
        let axis = th + s.yaw;
        for (i, &(id, lx, ly)) in landmarks.iter().enumerate() {
            let (dx, dy) = (lx - sx, ly - sy);
            let range = dx.hypot(dy);
            let bearing = wrap_angle(dy.atan2(dx) - axis);
            if range > s.max_range || bearing.abs() > s.half_fov {
                continue;
            }
            sightings += 1;
            let m = &mut markov[i];
            let (mut e_range, mut e_bearing) = (
                gauss(&mut rng, s.sigma_range),
                gauss(&mut rng, s.sigma_bearing),
            );
            if let Some(c) = correlated {
                let a = (-(t - m.time) / c.tau).exp();
                let b = (1.0 - a * a).max(0.0).sqrt();
                m.range = a * m.range + b * gauss(&mut rng, c.sigma_range);
                m.bearing = a * m.bearing + b * gauss(&mut rng, c.sigma_bearing);
                m.time = t;
                e_range += m.range;
                e_bearing += m.bearing;
            }
            // A range is >= 0: a noisy one below 0 is reflected.
            let (mut z_range, mut z_bearing) =
                ((range + e_range).abs(), wrap_angle(bearing + e_bearing));
            if rng.random::<f64>() < s.outliers {
                z_range = s.max_range * rng.random::<f64>();
                z_bearing = s.half_fov * (2.0 * rng.random::<f64>() - 1.0);
            }
            match s.kind {
                SensorKind::RangeBearing => {
                    let _ = writeln!(lines, "measurement,{t},{id},{z_range},{z_bearing}");
                }
                SensorKind::RangeOnly => {
                    let _ = writeln!(lines, "range,{t},{id},{z_range}");
                }
            }
        }
    }

    let mut text = String::with_capacity(lines.len() + 64 * (odometry.len() + landmarks.len()));
    let version = match s.kind {
        SensorKind::RangeBearing => 2,
        SensorKind::RangeOnly => 3,
    };
    let _ = writeln!(text, "# Locus log v{version}");
    let _ = writeln!(
        text,
        "# simulated robot {} of the family (locus_sim::family), seed {seed}: {}",
        member.name, member.about
    );
    // The mount's x is known; its yaw is not (the log says 0).
    let _ = writeln!(text, "sensor,{},0,0", s.mount_x);
    for (id, x, y) in &landmarks {
        let _ = writeln!(text, "landmark,{id},{x},{y}");
    }
    for (t, v, w) in &odometry {
        let _ = writeln!(text, "odometry,{t},{v},{w}");
    }
    text.push_str(&lines);
    let truth_dt = 1.0 / member.truth_rate;
    for i in 0.. {
        let t = micro(T0 + i as f64 * truth_dt);
        if t > t_end {
            break;
        }
        let [x, y, th] = path.pose_at(t);
        let theta = wrap_angle(th + member.truth_heading_offset);
        let _ = writeln!(text, "truth,{t},{x},{y},{theta}");
    }
    Generated {
        text,
        truth,
        path,
        landmarks,
        sightings,
        scans,
    }
}
