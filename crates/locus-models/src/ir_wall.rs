//! Two IR range sensors observing an axis-aligned wall (paper 001, eq. 3-5,
//! 17-20, with the spec's fixes).
//!
//! # Geometry
//! Two Sharp-type sensors on the robot's right side point to the right
//! (perpendicular to the heading), `L` apart along the heading: `s1` in front,
//! `s2` behind. Their mounting centre is `e` to the right of and `c` ahead of
//! the robot's centre (the paper's case is `e = c = 0`). Readings `d_s1`,
//! `d_s2` are ranges in metres (useful range 0.04-0.30 m; an observation exists
//! only when both read below 0.30 m: the caller's data association decides).
//!
//! # Observation (eq. 3-5)
//! ```text
//! ObsAng = atan((d_s1 - d_s2) / L)           d_w = (d_s1 + d_s2)/2 cos(ObsAng)   (eq. 3)
//! D      = d_w + e cos(ObsAng) - c sin(ObsAng)   distance from the robot centre to the wall
//! z      = [w - side * D;  theta_wall + ObsAng]                                  (eq. 4, 5)
//! ```
//! where the wall is the line `x = w` (or `y = w`) and `side = +1` if the
//! sensors look towards +x (+y), `-1` otherwise. For the paper's arena this is
//! `z = [Lw - d_w; pi/2 + ObsAng]` for `wall_x+` (\[fix\]: the paper's
//! `pi/2 - ObsAng`; with s1 in front a rotation away from the wall makes
//! ObsAng positive for every wall).
//!
//! # Model
//! `h(X) = [x; theta]` for x walls, `[y; theta]` for y walls;
//! `H = [[C1, C2, 0], [0, 0, 1]]` (eq. 17). The sensor noise
//! `r = [e_ds1, e_ds2]`, `R = diag(R11, R22)` (m^2), enters through
//! `V = dz/dr` (eq. 18-20, extended to the offsets):
//! ```text
//! k = L / (L^2 + (d_s1 - d_s2)^2)       a = cos(ObsAng)/2     b = -(d_s1 + d_s2)/2 sin(ObsAng) k
//! g = -(e sin(ObsAng) + c cos(ObsAng)) k
//! V = [[sgn (a + b + g), sgn (a - b - g)], [k, -k]]     sgn = -side
//! ```
//! so `V R V^T` is full even for a diagonal `R`. The innovation is `z - h(X)`
//! with the heading wrapped (\[fix\]: the paper writes `h - z`).

use locus_core::nalgebra::{Matrix2, SMatrix, SVector, Vector2};
use locus_core::{MeasurementModel, Scalar, cast, wrap_angle};

/// Which coordinate an axis-aligned wall fixes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WallAxis {
    /// A wall `x = w` (observes x and theta).
    X,
    /// A wall `y = w` (observes y and theta).
    Y,
}

/// The direction the sensors look towards the wall, along the wall's axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Sensors look towards +x (or +y).
    Positive,
    /// Sensors look towards -x (or -y).
    Negative,
}

/// An axis-aligned wall as the IR pair sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisWall<T> {
    /// Which coordinate the wall fixes.
    pub axis: WallAxis,
    /// The wall's coordinate `w` (m): the line `x = w` or `y = w`.
    pub coordinate: T,
    /// The direction the sensors look towards the wall.
    pub side: Side,
}

impl<T: Scalar> AxisWall<T> {
    /// `wall_x+` of the paper: the line `x = +lw`, seen looking towards +x.
    pub fn x_plus(lw: T) -> Self {
        Self {
            axis: WallAxis::X,
            coordinate: lw,
            side: Side::Positive,
        }
    }
    /// `wall_x-`: the line `x = -lw`, seen looking towards -x.
    pub fn x_minus(lw: T) -> Self {
        Self {
            axis: WallAxis::X,
            coordinate: -lw,
            side: Side::Negative,
        }
    }
    /// `wall_y+`: the line `y = +lw`, seen looking towards +y.
    pub fn y_plus(lw: T) -> Self {
        Self {
            axis: WallAxis::Y,
            coordinate: lw,
            side: Side::Positive,
        }
    }
    /// `wall_y-`: the line `y = -lw`, seen looking towards -y.
    pub fn y_minus(lw: T) -> Self {
        Self {
            axis: WallAxis::Y,
            coordinate: -lw,
            side: Side::Negative,
        }
    }

    /// `+1` if the sensors look towards +x/+y, `-1` otherwise.
    pub fn side_sign(&self) -> T {
        match self.side {
            Side::Positive => T::one(),
            Side::Negative => -T::one(),
        }
    }

    /// The robot heading (rad) at which right-pointing sensors look straight at
    /// the wall: `theta_wall` of eq. 4-5 (x+: pi/2, x-: -pi/2, y+: pi, y-: 0).
    pub fn theta_wall(&self) -> T {
        let half_pi = T::frac_pi_2();
        match (self.axis, self.side) {
            (WallAxis::X, Side::Positive) => half_pi,
            (WallAxis::X, Side::Negative) => -half_pi,
            (WallAxis::Y, Side::Positive) => T::pi(),
            (WallAxis::Y, Side::Negative) => T::zero(),
        }
    }
}

/// Mounting of the IR pair on the robot (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IrPair<T> {
    /// Spacing `L` between the two sensors along the heading (> 0).
    pub spacing: T,
    /// Lateral offset `e` of the pair's centre to the right of the robot centre.
    pub lateral_offset: T,
    /// Longitudinal offset `c` of the pair's centre ahead of the robot centre.
    pub forward_offset: T,
}

impl<T: Scalar> IrPair<T> {
    /// The paper's mounting: sensors `spacing` apart, centred on the robot (e = c = 0).
    pub fn centred(spacing: T) -> Self {
        Self {
            spacing,
            lateral_offset: T::zero(),
            forward_offset: T::zero(),
        }
    }

    /// The pair's sensing ray at the pose `[x, y, theta]` (m, m, rad): its
    /// origin, the pair's centre (`forward_offset` ahead, `lateral_offset`
    /// to the right), and its unit direction, to the right of the heading.
    /// Data association casts it in the map ([`crate::associate_ir_wall`]).
    pub fn sensing_ray(&self, x: &SVector<T, 3>) -> (Vector2<T>, Vector2<T>) {
        let (s, c) = x[2].sin_cos();
        let origin = Vector2::new(
            x[0] + self.forward_offset * c + self.lateral_offset * s,
            x[1] + self.forward_offset * s - self.lateral_offset * c,
        );
        (origin, Vector2::new(s, -c))
    }

    /// `(ObsAng, D)`: the angle of the wall relative to the sensing direction
    /// (rad) and the distance from the robot centre to the wall (m), from the
    /// two readings (eq. 3 with the offsets).
    pub fn angle_and_distance(&self, ds1: T, ds2: T) -> (T, T) {
        let ang = ((ds1 - ds2) / self.spacing).atan();
        let (s, c) = ang.sin_cos();
        let dw = (ds1 + ds2) * cast::<T>(0.5) * c;
        (ang, dw + self.lateral_offset * c - self.forward_offset * s)
    }
}

/// One observation of a wall by the IR pair: the readings, the wall they are
/// associated with, and the sensor noise. Implements
/// [`MeasurementModel<T, 3, 2>`] with `z` from [`IrPairObservation::z`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IrPairObservation<T> {
    /// Mounting of the pair.
    pub pair: IrPair<T>,
    /// The wall the observation is associated with.
    pub wall: AxisWall<T>,
    /// Front sensor reading `d_s1` (m).
    pub ds1: T,
    /// Rear sensor reading `d_s2` (m).
    pub ds2: T,
    /// Variance of the front reading `R11` (m^2).
    pub r11: T,
    /// Variance of the rear reading `R22` (m^2).
    pub r22: T,
}

impl<T: Scalar> IrPairObservation<T> {
    /// The observation `z = [x or y; theta]` (m, rad) the readings give (eq. 4-5).
    pub fn z(&self) -> SVector<T, 2> {
        observe(&self.pair, &self.wall, self.ds1, self.ds2)
    }

    /// `V = dz/d(d_s1, d_s2)` at the readings (eq. 18-20 with the offsets).
    /// `cos(ObsAng)` and `sin(ObsAng)` of `ObsAng = atan((d_s1 - d_s2) / L)`
    /// are `L / h` and `(d_s1 - d_s2) / h` with `h = sqrt(L^2 + (d_s1 - d_s2)^2)`:
    /// one square root instead of `atan` and `sin_cos` (the same values to
    /// rounding; checked against finite differences of [`observe`]).
    pub fn v(&self) -> SMatrix<T, 2, 2> {
        let l = self.pair.spacing;
        let diff = self.ds1 - self.ds2;
        let den = l * l + diff * diff;
        let k = l / den;
        let inv_hyp = T::one() / den.sqrt();
        let (s, c) = (diff * inv_hyp, l * inv_hyp);
        let half = cast::<T>(0.5);
        let a = c * half;
        let b = -(self.ds1 + self.ds2) * half * s * k;
        let g = -(self.pair.lateral_offset * s + self.pair.forward_offset * c) * k;
        let sgn = -self.wall.side_sign();
        Matrix2::new(sgn * (a + b + g), sgn * (a - b - g), k, -k)
    }

    /// True if every reading, noise value and mounting parameter is finite.
    pub fn is_finite(&self) -> bool {
        [
            self.ds1,
            self.ds2,
            self.r11,
            self.r22,
            self.pair.spacing,
            self.wall.coordinate,
        ]
        .iter()
        .all(|v| v.is_finite())
            && self.pair.lateral_offset.is_finite()
            && self.pair.forward_offset.is_finite()
    }
}

/// The observation `z` from the readings (eq. 3-5 with offsets); a free
/// function so its Jacobian `V` can be checked by finite differences.
pub fn observe<T: Scalar>(pair: &IrPair<T>, wall: &AxisWall<T>, ds1: T, ds2: T) -> SVector<T, 2> {
    let (ang, dist) = pair.angle_and_distance(ds1, ds2);
    Vector2::new(
        wall.coordinate - wall.side_sign() * dist,
        wrap_angle(wall.theta_wall() + ang),
    )
}

impl<T: Scalar> MeasurementModel<T, 3, 2> for IrPairObservation<T> {
    /// Eq. 14-17: the distance along the wall's axis and the heading; `H`
    /// selects them.
    fn evaluate(
        &self,
        x: &SVector<T, 3>,
        jacobian: Option<&mut SMatrix<T, 2, 3>>,
    ) -> Option<SVector<T, 2>> {
        let (o, z) = (T::one(), T::zero());
        let (pos, h) = match self.wall.axis {
            WallAxis::X => (x[0], SMatrix::<T, 2, 3>::new(o, z, z, z, z, o)),
            WallAxis::Y => (x[1], SMatrix::<T, 2, 3>::new(z, o, z, z, z, o)),
        };
        if let Some(j) = jacobian {
            *j = h;
        }
        Some(Vector2::new(pos, x[2]))
    }

    /// `V R V^T` for the diagonal `R`, expanded (exactly symmetric).
    fn noise(&self, _x: &SVector<T, 3>) -> SMatrix<T, 2, 2> {
        let v = self.v();
        let (a, b) = (v[(0, 0)], v[(0, 1)]);
        let (c, d) = (v[(1, 0)], v[(1, 1)]);
        let (r1, r2) = (self.r11, self.r22);
        let s00 = r1 * a * a + r2 * b * b;
        let s01 = r1 * a * c + r2 * b * d;
        let s11 = r1 * c * c + r2 * d * d;
        Matrix2::new(s00, s01, s01, s11)
    }

    fn residual(&self, z: &SVector<T, 2>, z_hat: &SVector<T, 2>) -> SVector<T, 2> {
        Vector2::new(z[0] - z_hat[0], wrap_angle(z[1] - z_hat[1]))
    }

    /// `H` selects `x` (or `y`) and `theta` (eq. 17): `P H^T` is two columns
    /// of `P` and `H P H^T` its 2x2 sub-block, with no multiplication.
    #[inline]
    fn project(
        &self,
        _x: &SVector<T, 3>,
        _h: &SMatrix<T, 2, 3>,
        p: &SMatrix<T, 3, 3>,
    ) -> (SMatrix<T, 3, 2>, SMatrix<T, 2, 2>) {
        // One arm per axis, so every index is a constant and P can stay in
        // registers.
        let select = |k: usize| {
            let pht = SMatrix::<T, 3, 2>::new(
                p[(0, k)],
                p[(0, 2)],
                p[(1, k)],
                p[(1, 2)],
                p[(2, k)],
                p[(2, 2)],
            );
            let hph = Matrix2::new(p[(k, k)], p[(k, 2)], p[(2, k)], p[(2, 2)]);
            (pht, hph)
        };
        let (pht, hph) = match self.wall.axis {
            WallAxis::X => select(0),
            WallAxis::Y => select(1),
        };
        (pht, hph)
    }
}
