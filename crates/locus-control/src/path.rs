//! Paper 001's path controller: the `GoXYTheta`, `FollowLine` and `FollowCircle`
//! routines and `FollowPath`, a fixed-capacity sequence of them (seed 001, section
//! "A. Control Module"; spec `MODELS.md` section 3).
//!
//! Every routine maps the current pose estimate `(x, y, theta)` (world frame, metres
//! and radians, `theta` measured counter-clockwise from the x axis) to a body twist
//! [`Twist`], the unicycle command `(V, W)`: linear speed in m/s, turn rate in
//! rad/s, positive counter-clockwise. [`wheel_speeds`] converts it to the two wheel speeds with equation (1)
//! of the paper, `V1 = V + b W / 2` (right wheel) and `V2 = V - b W / 2` (left wheel).
//!
//! The steering law, common to the line and the circle, is a saturated
//! "heading-to-path" law (the paper gives no equations, so this is an assumption):
//! with a signed cross-track error `e` (metres, positive to the left of the direction
//! of travel) the desired heading is the path tangent minus `atan(k_cross e)`, and
//! `W = W_ff + k_heading wrap(theta_d - theta)`, where `W_ff` is the path-curvature
//! feed-forward (`+-V / r` on a circle, 0 on a line). `V = V_ref max(cos(heading
//! error), 0)`, so the robot slows down, and at a corner turns on the spot, while it
//! points away from the path. Both outputs are then clamped to `|V| <= V_ref`,
//! `|W| <= W_ref`.

use core::f64::consts::FRAC_PI_2;

/// A pose estimate in the world frame (m, m, rad): Locus's one planar pose.
/// Its heading may take any value (it is wrapped where a difference of
/// angles is formed).
pub type Pose = locus_core::Pose<f64>;

/// A point in the world frame (m).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Point {
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
}

impl Point {
    /// A point from its coordinates (m).
    #[must_use]
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }
}

/// Direction of travel around a circle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Clockwise (seen from above, z up): turn rate negative.
    Cw,
    /// Counter-clockwise: turn rate positive.
    Ccw,
}

impl Direction {
    /// `+1.0` for [`Direction::Ccw`], `-1.0` for [`Direction::Cw`].
    #[must_use]
    pub const fn sign(self) -> f64 {
        match self {
            Self::Cw => -1.0,
            Self::Ccw => 1.0,
        }
    }
}

/// The body twist commanded by a routine: the unicycle command `(V, W)` of the
/// robot's reference point (not wheel speeds: [`wheel_speeds`] turns it into
/// those), the output of every routine.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Twist {
    /// Linear speed V (m/s), positive forwards.
    pub v: f64,
    /// Turn rate W (rad/s), positive counter-clockwise.
    pub w: f64,
    /// `true` once the routine (or the whole path) has finished; `v` and `w` are then 0.
    pub done: bool,
}

impl Twist {
    /// The stop command of a finished routine: `v = w = 0`, `done = true`.
    pub const DONE: Self = Self {
        v: 0.0,
        w: 0.0,
        done: true,
    };
}

/// Wheel speeds `(V1, V2)` (m/s) for a body twist, paper 001 equation (1):
/// `V1 = V + b W / 2` (right wheel), `V2 = V - b W / 2` (left wheel).
///
/// `wheelbase` is `b`, the distance between the wheels (m).
#[must_use]
pub fn wheel_speeds(twist: Twist, wheelbase: f64) -> (f64, f64) {
    let half = wheelbase * twist.w / 2.0;
    (twist.v + half, twist.v - half)
}

/// Controller parameters: reference speeds (which also act as saturation), gains and
/// tolerances. See [`Config::default`] for the default values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// Reference (cruise) linear speed `V_ref` (m/s), also the limit on `|V|`.
    /// Default 0.1 m/s. Must be positive.
    pub v_ref: f64,
    /// Reference turn rate `W_ref` (rad/s), the limit on `|W|`. Default 1.5 rad/s.
    /// Must be positive and, on a circle, above `V_ref / radius`.
    pub w_ref: f64,
    /// Cross-track gain `k_cross` (rad/m): desired heading offset is
    /// `atan(k_cross e)` for a cross-track error `e`. Default 10 rad/m.
    pub k_cross: f64,
    /// Heading gain `k_heading` (1/s): `W = k_heading * heading error`. Default 4 /s.
    pub k_heading: f64,
    /// Position gain `k_pos` (1/s) of `GoXYTheta`: `V <= k_pos * distance`, so the
    /// robot slows down near the target. Default 1 /s.
    pub k_pos: f64,
    /// Position tolerance of `GoXYTheta` (m). Default 0.01 m.
    pub pos_tol: f64,
    /// Heading tolerance of `GoXYTheta` (rad). Default 0.02 rad.
    pub heading_tol: f64,
}

impl Default for Config {
    /// `v_ref` 0.1 m/s, `w_ref` 1.5 rad/s, `k_cross` 10 rad/m, `k_heading` 4 /s,
    /// `k_pos` 1 /s, `pos_tol` 0.01 m, `heading_tol` 0.02 rad.
    fn default() -> Self {
        Self {
            v_ref: 0.1,
            w_ref: 1.5,
            k_cross: 10.0,
            k_heading: 4.0,
            k_pos: 1.0,
            pos_tol: 0.01,
            heading_tol: 0.02,
        }
    }
}

impl Config {
    /// Clamps `(v, w)` to `|v| <= v_ref`, `|w| <= w_ref` (a NaN becomes 0).
    fn saturate(&self, v: f64, w: f64) -> Twist {
        Twist {
            v: clamp(v, self.v_ref),
            w: clamp(w, self.w_ref),
            done: false,
        }
    }
}

fn clamp(value: f64, limit: f64) -> f64 {
    if value.is_nan() {
        0.0
    } else {
        value.clamp(-limit, limit)
    }
}

pub use locus_core::wrap_angle;

/// One routine of paper 001, as plain data (its progress lives in [`Routine`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Segment {
    /// Reach the point `(x, y)` (m), then turn on the spot to heading `theta` (rad).
    /// Done when within [`Config::pos_tol`] of the point and
    /// [`Config::heading_tol`] of the heading.
    GoXYTheta {
        /// Target x (m).
        x: f64,
        /// Target y (m).
        y: f64,
        /// Final heading (rad).
        theta: f64,
    },
    /// Follow the directed line from `from` to `to`; done when the projection of the
    /// position on the line is past `to`. `from == to` is degenerate: done at once.
    FollowLine {
        /// Start point (m).
        from: Point,
        /// End point (m); the direction of travel is `from -> to`.
        to: Point,
    },
    /// Follow a circle. With `arc: None` it never finishes; with `Some(angle)` it is
    /// done once the robot has swept `angle` (rad) (positive) around the centre in
    /// the direction of travel, counted from the first command.
    FollowCircle {
        /// Centre (m).
        centre: Point,
        /// Radius (m), positive; a radius that is not (0, NaN) is degenerate and the
        /// routine is done at once.
        radius: f64,
        /// Direction of travel.
        direction: Direction,
        /// Angle to sweep before finishing (rad), or `None` to circle forever.
        arc: Option<f64>,
    },
}

/// A source of body twists ([`Twist`]) from pose estimates.
pub trait Controller {
    /// The body twist for the current pose estimate. Call once per control step; a
    /// finished controller keeps returning [`Twist::DONE`].
    fn command(&mut self, pose: Pose) -> Twist;
}

/// Progress of a routine (private to the steering laws).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Progress {
    /// Nothing yet.
    Start,
    /// `GoXYTheta` turning on the spot at the target.
    Turning,
    /// `FollowCircle`: last polar angle (rad) and angle swept so far (rad).
    Swept { last: f64, swept: f64 },
    /// Finished.
    Done,
}

/// A [`Segment`] being executed with a [`Config`]: the controller of one routine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Routine {
    segment: Segment,
    config: Config,
    progress: Progress,
}

impl Routine {
    /// A routine at its start.
    #[must_use]
    pub const fn new(segment: Segment, config: Config) -> Self {
        Self {
            segment,
            config,
            progress: Progress::Start,
        }
    }

    /// The segment being followed.
    #[must_use]
    pub const fn segment(&self) -> &Segment {
        &self.segment
    }

    /// Whether the routine has finished.
    #[must_use]
    pub fn is_done(&self) -> bool {
        self.progress == Progress::Done
    }

    /// Restarts the routine.
    pub fn reset(&mut self) {
        self.progress = Progress::Start;
    }

    fn finish(&mut self) -> Twist {
        self.progress = Progress::Done;
        Twist::DONE
    }

    fn go_xy_theta(&mut self, pose: Pose, x: f64, y: f64, theta: f64) -> Twist {
        let c = self.config;
        let (dx, dy) = (x - pose.x, y - pose.y);
        let distance = libm::hypot(dx, dy);
        // Hysteresis: leave the turning phase only if pushed well off the point.
        let turning = match self.progress {
            Progress::Turning => distance <= 2.0 * c.pos_tol,
            _ => distance <= c.pos_tol,
        };
        if turning {
            self.progress = Progress::Turning;
            let error = wrap_angle(theta - pose.theta);
            if libm::fabs(error) <= c.heading_tol {
                return self.finish();
            }
            return c.saturate(0.0, c.k_heading * error);
        }
        self.progress = Progress::Start;
        let bearing = wrap_angle(libm::atan2(dy, dx) - pose.theta);
        let speed = c.v_ref.min(c.k_pos * distance);
        c.saturate(speed * libm::cos(bearing).max(0.0), c.k_heading * bearing)
    }

    /// Shared steering: drive along `tangent` (rad) with cross-track error `e` (m)
    /// (positive left) and signed path curvature `curvature` (1/m) (feed-forward
    /// `W_ff = V curvature`).
    fn steer(&self, pose: Pose, tangent: f64, e: f64, curvature: f64) -> Twist {
        let c = self.config;
        let desired = tangent - libm::atan(c.k_cross * e);
        let error = wrap_angle(desired - pose.theta);
        let v = c.v_ref * libm::cos(error).max(0.0);
        c.saturate(v, v * curvature + c.k_heading * error)
    }

    fn follow_line(&mut self, pose: Pose, from: Point, to: Point) -> Twist {
        let (lx, ly) = (to.x - from.x, to.y - from.y);
        let length = libm::hypot(lx, ly);
        if length <= 0.0 || length.is_nan() {
            return self.finish();
        }
        let (ux, uy) = (lx / length, ly / length);
        let (px, py) = (pose.x - from.x, pose.y - from.y);
        if ux * px + uy * py >= length {
            return self.finish();
        }
        let e = ux * py - uy * px;
        self.steer(pose, libm::atan2(uy, ux), e, 0.0)
    }

    fn follow_circle(
        &mut self,
        pose: Pose,
        centre: Point,
        radius: f64,
        direction: Direction,
        arc: Option<f64>,
    ) -> Twist {
        if radius.is_nan() || radius <= 0.0 {
            return self.finish();
        }
        let s = direction.sign();
        let (rx, ry) = (pose.x - centre.x, pose.y - centre.y);
        let rho = libm::hypot(rx, ry);
        let phi = libm::atan2(ry, rx);
        if let Some(arc) = arc {
            let swept = match self.progress {
                Progress::Swept { last, swept } => swept + s * wrap_angle(phi - last),
                _ => 0.0,
            };
            if swept >= arc {
                return self.finish();
            }
            self.progress = Progress::Swept { last: phi, swept };
        }
        // Tangent heading s * pi/2 from the radius; outside (rho > radius) is to the
        // right of travel for Ccw, the left for Cw, hence e = -s (rho - radius).
        let e = -s * (rho - radius);
        self.steer(pose, phi + s * FRAC_PI_2, e, s / radius)
    }
}

impl Controller for Routine {
    fn command(&mut self, pose: Pose) -> Twist {
        if self.is_done() {
            return Twist::DONE;
        }
        match self.segment {
            Segment::GoXYTheta { x, y, theta } => self.go_xy_theta(pose, x, y, theta),
            Segment::FollowLine { from, to } => self.follow_line(pose, from, to),
            Segment::FollowCircle {
                centre,
                radius,
                direction,
                arc,
            } => self.follow_circle(pose, centre, radius, direction, arc),
        }
    }
}

/// Half the side of the spec's square path (m) (side `Lp = 1.7` m, corners at
/// `(+-0.85, +-0.85)`).
pub const SQUARE_HALF_SIDE: f64 = 0.85;

/// The four sides of a square centred on the origin with corners at
/// `(+-half_side, +-half_side)`, counter-clockwise from `(-h, -h)`: along `y = -h`
/// towards +x, then `x = +h`, `y = +h`, `x = -h`. With the walls outside the square,
/// they are on the robot's right.
#[must_use]
pub const fn square(half_side: f64) -> [Segment; 4] {
    let h = half_side;
    let a = Point::new(-h, -h);
    let b = Point::new(h, -h);
    let c = Point::new(h, h);
    let d = Point::new(-h, h);
    [
        Segment::FollowLine { from: a, to: b },
        Segment::FollowLine { from: b, to: c },
        Segment::FollowLine { from: c, to: d },
        Segment::FollowLine { from: d, to: a },
    ]
}

/// `FollowPath`: up to `N` segments run in order, switching to the next in the same
/// step that the current one finishes. No allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FollowPath<const N: usize> {
    segments: [Segment; N],
    index: usize,
    current: Option<Routine>,
    config: Config,
}

impl<const N: usize> FollowPath<N> {
    /// A path over `segments`, at its first segment. `N = 0` is valid: done at once.
    #[must_use]
    pub fn new(segments: [Segment; N], config: Config) -> Self {
        let current = segments.first().map(|s| Routine::new(*s, config));
        Self {
            segments,
            index: 0,
            current,
            config,
        }
    }

    /// Index of the segment being followed (`N` once the path is done).
    #[must_use]
    pub const fn index(&self) -> usize {
        self.index
    }

    /// The segments.
    #[must_use]
    pub const fn segments(&self) -> &[Segment; N] {
        &self.segments
    }

    /// Whether every segment has finished.
    #[must_use]
    pub const fn is_done(&self) -> bool {
        self.current.is_none()
    }

    /// Restarts from the first segment.
    pub fn reset(&mut self) {
        *self = Self::new(self.segments, self.config);
    }

    /// The parameters in use.
    #[must_use]
    pub const fn config(&self) -> &Config {
        &self.config
    }

    /// Replaces the parameters (speeds, gains, tolerances), keeping the
    /// progress along the path: the current segment continues with the new
    /// values (the teaching UI changes gains while the robot drives).
    pub fn set_config(&mut self, config: Config) {
        self.config = config;
        if let Some(routine) = self.current.as_mut() {
            routine.config = config;
        }
    }
}

impl FollowPath<4> {
    /// The square of spec section 3: side 1.7 m centred on the origin,
    /// counter-clockwise from `(-0.85, -0.85)` (see [`square`]).
    #[must_use]
    pub fn square(config: Config) -> Self {
        Self::new(square(SQUARE_HALF_SIDE), config)
    }
}

impl<const N: usize> Controller for FollowPath<N> {
    fn command(&mut self, pose: Pose) -> Twist {
        while let Some(routine) = self.current.as_mut() {
            let command = routine.command(pose);
            if !command.done {
                return command;
            }
            self.index += 1;
            self.current = self
                .segments
                .get(self.index)
                .map(|s| Routine::new(*s, self.config));
        }
        Twist::DONE
    }
}
