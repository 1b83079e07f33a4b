//! The true motion of a family member: piecewise-constant velocities on a
//! regular grid of knots, integrated exactly (arcs).

use locus_core::wrap_angle;

/// The pose `[x m, y m, theta rad]` after moving at forward speed `v`
/// (m/s) and turn rate `omega` (rad/s) for `tau` seconds from `pose`: the
/// exact unicycle arc (a straight line when `omega` is below 1e-12 rad/s).
/// The heading is wrapped to (-pi, pi].
#[must_use]
pub fn arc(pose: [f64; 3], v: f64, omega: f64, tau: f64) -> [f64; 3] {
    let [x, y, th] = pose;
    let th1 = th + omega * tau;
    if omega.abs() < 1e-12 {
        return [
            x + v * tau * th.cos(),
            y + v * tau * th.sin(),
            wrap_angle(th1),
        ];
    }
    let k = v / omega;
    [
        x + k * (th1.sin() - th.sin()),
        y - k * (th1.cos() - th.cos()),
        wrap_angle(th1),
    ]
}

/// A true trajectory: at rest at `start` until `first` (s), then over each
/// period `[first + k dt, first + (k + 1) dt)` the constant velocities of
/// knot `k` (the last held for ever).
#[derive(Debug, Clone, PartialEq)]
pub struct TruePath {
    first: f64,
    dt: f64,
    start: [f64; 3],
    /// Pose at the start of each period and the velocities over it
    /// (m, m, rad; m/s, rad/s).
    knots: Vec<([f64; 3], f64, f64)>,
}

impl TruePath {
    /// An empty path at rest at `start` (m, m, rad) until `first` (s), with
    /// periods of `dt` seconds (> 0).
    #[must_use]
    pub fn new(start: [f64; 3], first: f64, dt: f64) -> Self {
        Self {
            first,
            dt,
            start,
            knots: Vec::new(),
        }
    }

    /// The pose at the end of the periods so far (where the next starts).
    #[must_use]
    pub fn end(&self) -> [f64; 3] {
        self.knots
            .last()
            .map_or(self.start, |&(p, v, w)| arc(p, v, w, self.dt))
    }

    /// Appends a period at forward speed `v` (m/s) and turn rate `omega`
    /// (rad/s).
    pub fn push(&mut self, v: f64, omega: f64) {
        let p = self.end();
        self.knots.push((p, v, omega));
    }

    /// The true velocities `(v m/s, omega rad/s)` at time `t` (s).
    #[must_use]
    pub fn velocity_at(&self, t: f64) -> (f64, f64) {
        match self.period(t) {
            None => (0.0, 0.0),
            Some(k) => (self.knots[k].1, self.knots[k].2),
        }
    }

    /// The index of the period holding `t`, `None` before the first.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    fn period(&self, t: f64) -> Option<usize> {
        if self.knots.is_empty() || t < self.first {
            return None;
        }
        let k = ((t - self.first) / self.dt).floor() as usize;
        Some(k.min(self.knots.len() - 1))
    }

    /// The true pose at time `t` (s): m, m, rad in (-pi, pi].
    #[must_use]
    pub fn pose_at(&self, t: f64) -> [f64; 3] {
        match self.period(t) {
            None => self.start,
            Some(k) => {
                #[allow(clippy::cast_precision_loss)]
                let since = t - (self.first + k as f64 * self.dt);
                let (p, v, w) = self.knots[k];
                arc(p, v, w, since)
            }
        }
    }
}
