//! 6-DOF pose of a rigid body from a fixed camera seeing marks on it (paper
//! 002, eq. 1-10 and 18-19; spec `MODELS.md` section 4).
//!
//! # State (eq. 2)
//! `x = [tx, ty, tz, phi, theta, psi]`: the translation `T = (tx, ty, tz)` (m)
//! of the body origin in the camera frame and the roll, pitch and yaw angles
//! (rad) of the body relative to the camera. The camera frame is the usual
//! pinhole frame: `z_c` along the optical axis (in front of the camera is
//! `z_c > 0`), `x_c` towards increasing pixel column `u`, `y_c` towards
//! increasing pixel row `v`.
//!
//! # Rotation (eq. 3)
//! `R = Rz(psi) Ry(theta) Rx(phi)`, each factor `exp(hat(e_i) angle)`, with
//! `hat(w) v = w x v` (eq. 4). Its partial derivatives (eq. 19, with the
//! spec's **\[fix\]** for the pitch, garbled in the paper's text):
//! ```text
//! dR/dphi   = R hat(e1)
//! dR/dtheta = Rz(psi) Ry(theta) hat(e2) Rx(phi)
//! dR/dpsi   = hat(e3) R
//! ```
//!
//! # Measurement (eq. 5-10)
//! For mark `j` with body-frame coordinates `X_O` (m, eq. 6):
//! ```text
//! X_C = T + R X_O                           camera frame, m           (eq. 7)
//! n   = (x_c / z_c, y_c / z_c)              normalised pinhole, -     (eq. 8)
//! d   = (1 + Kc1 r^2) n,  r^2 = |n|^2       radial distortion, -      (eq. 9)
//! y   = (l_x d_x + o_x, l_y d_y + o_y)      pixels, px                (eq. 10)
//! ```
//! and `h(x)` stacks the `m` pixel pairs `[u_1, v_1, ..., u_m, v_m]` (eq. 5).
//! Measurement noise `Theta = sigma_p^2 I` (px^2), `sigma_p = 2 px`.
//!
//! # Jacobian (eq. 18, with the pitch column the paper's text omits)
//! ```text
//! C_j = diag(l_x, l_y)
//!     * [[1 + 3Kc1 n_x^2 + Kc1 n_y^2, 2Kc1 n_x n_y],
//!        [2Kc1 n_x n_y, 1 + Kc1 n_x^2 + 3Kc1 n_y^2]]
//!     * [[1/z_c, 0, -x_c/z_c^2], [0, 1/z_c, -y_c/z_c^2]]
//!     * [ I3 | dR/dphi X_O | dR/dtheta X_O | dR/dpsi X_O ]
//! ```
//! (px/m in the translation columns, px/rad in the angle columns.)
//!
//! # Valid domain
//! Every mark strictly in front of the camera, `z_c > min_depth`
//! ([`CameraMarks::min_depth`], default [`DEFAULT_MIN_DEPTH`] = 0.05 m, the
//! spec's divergence rule of the domain-of-attraction study); elsewhere
//! [`CameraMarks`] predicts no measurement (`h` returns `None`). The
//! measurement is periodic in the three angles; the Euler parametrisation is
//! singular (gimbal lock) at `theta = +-pi/2`, where `h` is still smooth but
//! two angle columns of `C` become dependent.
//!
//! # Measurement dimension `2M` on stable Rust
//! Const generics cannot compute `2 * M` in a type on stable, so the model is
//! [`CameraMarks<T, M, D>`] with **both** the mark count `M` and the
//! measurement dimension `D` as parameters, tied by a compile-time assertion
//! `D == 2 * M` (a post-monomorphisation `const` assertion: a mismatched
//! instantiation such as `CameraMarks<f64, 4, 6>` fails to build as soon as it
//! is constructed or used as a model). Aliases name the useful cases:
//! [`CameraMarks4`] (`M = 4`, `D = 8`, the paper's configuration) and
//! [`CameraMark`] (one mark, `D = 2`, for mark-by-mark processing). With `D`
//! in the type, `MeasurementModel<T, 6, D>` has exactly one impl per type, so
//! no call site needs a dimension annotation.
//!
//! # Motion (eq. 1, 23)
//! [`RandomWalk6`]: `dx/dt = delta`, `delta ~ N(0, Q)` white, `Q` a
//! continuous-time density, discretised exactly over a step `dt`.

use locus_core::nalgebra::{Matrix2, Matrix3, SMatrix, SVector, Vector2, Vector3};
use locus_core::{MeasurementModel, MotionJacobians, MotionModel, Scalar, cast, wrap_angle};

/// Default minimum depth `z_c` (m) of every mark for a measurement to exist:
/// the spec's divergence rule ("a mark comes within 0.05 m of the camera
/// plane").
pub const DEFAULT_MIN_DEPTH: f64 = 0.05;

/// Translation-velocity standard deviation `sigma_T` of paper 002 (eq. 23),
/// m/s: `Q` holds `sigma_T^2` (m^2/s as a density) for `tx, ty, tz`.
pub const SIGMA_T: f64 = 0.1;

/// Rotation-rate standard deviation `sigma_E` of paper 002 (eq. 23), rad/s:
/// `Q` holds `sigma_E^2` (rad^2/s as a density) for `phi, theta, psi`.
pub const SIGMA_E: f64 = 0.1396;

/// Pixel noise standard deviation `sigma_p` of paper 002 (px): the
/// measurement covariance is `Theta = sigma_p^2 I = 4 I` px^2.
pub const SIGMA_PIXEL: f64 = 2.0;

/// The paper-002 process-noise density `Q = diag(0.1^2 x3, 0.1396^2 x3)`
/// (eq. 23), in (m/s)^2 s = m^2/s for the translations and rad^2/s for the
/// angles (the paper states the variances of white velocity noise).
pub fn paper_q<T: Scalar>() -> SMatrix<T, 6, 6> {
    let t = cast::<T>(SIGMA_T * SIGMA_T);
    let e = cast::<T>(SIGMA_E * SIGMA_E);
    SMatrix::from_diagonal(&SVector::<T, 6>::from([t, t, t, e, e, e]))
}

/// The spec's \[assumed\] nominal pose of paper 002: `T = (0, 0, 2.5)` m (the
/// body 2.5 m in front of the camera, on its axis), all angles 0 rad.
pub fn nominal_pose<T: Scalar>() -> SVector<T, 6> {
    let z = T::zero();
    SVector::<T, 6>::from([z, z, cast(2.5), z, z, z])
}

/// The cross-product matrix `hat(w)` with `hat(w) v = w x v` (paper 002,
/// eq. 4).
#[inline]
pub fn hat<T: Scalar>(w: &Vector3<T>) -> Matrix3<T> {
    let z = T::zero();
    Matrix3::new(z, -w[2], w[1], w[2], z, -w[0], -w[1], w[0], z)
}

/// The rotation `R = Rz(psi) Ry(theta) Rx(phi)` of paper 002 (eq. 3) and its
/// factors, for roll `phi`, pitch `theta`, yaw `psi` (rad, any real value).
///
/// `R` maps body-frame coordinates to camera-frame coordinates. Build it once
/// per pose and reuse it for every mark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EulerRotation<T: Scalar> {
    /// `Rx(phi)`, rotation about the body x axis by the roll.
    pub rx: Matrix3<T>,
    /// `Ry(theta)`, rotation about the intermediate y axis by the pitch.
    pub ry: Matrix3<T>,
    /// `Rz(psi)`, rotation about the camera z axis by the yaw.
    pub rz: Matrix3<T>,
    /// `R = Rz(psi) Ry(theta) Rx(phi)`.
    pub r: Matrix3<T>,
}

impl<T: Scalar> EulerRotation<T> {
    /// The rotation for roll `phi`, pitch `theta`, yaw `psi` (rad).
    pub fn new(phi: T, theta: T, psi: T) -> Self {
        let (o, z) = (T::one(), T::zero());
        let (sp, cp) = phi.sin_cos();
        let (st, ct) = theta.sin_cos();
        let (ss, cs) = psi.sin_cos();
        let rx = Matrix3::new(o, z, z, z, cp, -sp, z, sp, cp);
        let ry = Matrix3::new(ct, z, st, z, o, z, -st, z, ct);
        let rz = Matrix3::new(cs, -ss, z, ss, cs, z, z, z, o);
        Self {
            rx,
            ry,
            rz,
            r: rz * (ry * rx),
        }
    }

    /// The rotation for the angle part `x[3..6]` of a state (eq. 2).
    pub fn from_state(x: &SVector<T, 6>) -> Self {
        Self::new(x[3], x[4], x[5])
    }

    /// `dR/dphi v = R hat(e1) v = R (e1 x v)` (eq. 19).
    #[inline]
    pub fn d_phi(&self, v: &Vector3<T>) -> Vector3<T> {
        // e1 x v = (0, -v_z, v_y).
        self.r * Vector3::new(T::zero(), -v[2], v[1])
    }

    /// `dR/dtheta v = Rz Ry hat(e2) Rx v` (eq. 19 with the spec's **\[fix\]**).
    #[inline]
    pub fn d_theta(&self, v: &Vector3<T>) -> Vector3<T> {
        // w = Rx v, hat(e2) w = e2 x w = (w_z, 0, -w_x), then Rz Ry.
        let w = self.rx * v;
        self.rz * (self.ry * Vector3::new(w[2], T::zero(), -w[0]))
    }

    /// `dR/dpsi v = hat(e3) R v = e3 x (R v)` (eq. 19).
    #[inline]
    pub fn d_psi(&self, v: &Vector3<T>) -> Vector3<T> {
        let w = self.r * v;
        Vector3::new(-w[1], w[0], T::zero())
    }
}

/// Intrinsic parameters of the camera (paper 002, eq. 9-10), from the
/// Camera Calibration Toolbox for Matlab.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics<T> {
    /// Focal lengths `l = (l_x, l_y)` (px per unit of normalised coordinate).
    pub focal: Vector2<T>,
    /// Principal point `o = (o_x, o_y)` (px).
    pub principal: Vector2<T>,
    /// Second-order radial distortion coefficient `Kc1` (dimensionless; the
    /// paper's lens has `Kc1 = -0.19457`, barrel distortion). The distortion
    /// map is invertible (and the model meaningful) while
    /// `1 + 3 Kc1 r^2 > 0`, i.e. `r^2 < 1.71` for the paper's lens: far
    /// outside any real image.
    pub kc1: T,
}

impl<T: Scalar> Intrinsics<T> {
    /// The paper's calibration: `l = (1865.33, 1868.57)` px,
    /// `o = (510.68, 619.68)` px, `Kc1 = -0.19457`.
    pub fn paper_002() -> Self {
        Self {
            focal: Vector2::new(cast(1865.33), cast(1868.57)),
            principal: Vector2::new(cast(510.68), cast(619.68)),
            kc1: cast(-0.19457),
        }
    }

    /// Pixel coordinates `(u, v)` (px) of a point `X_C` (m) in the camera
    /// frame: pinhole (eq. 8), radial distortion (eq. 9), pixels (eq. 10).
    /// Defined for `z_c != 0`; meaningful only for `z_c > 0` (the point in
    /// front of the camera), which the caller checks.
    #[inline]
    pub fn project(&self, xc: &Vector3<T>) -> Vector2<T> {
        let inv_z = T::one() / xc[2];
        let (nx, ny) = (xc[0] * inv_z, xc[1] * inv_z);
        let k = T::one() + self.kc1 * (nx * nx + ny * ny);
        Vector2::new(
            self.focal[0] * k * nx + self.principal[0],
            self.focal[1] * k * ny + self.principal[1],
        )
    }

    /// `d(u, v)/dX_C` (px/m, 2 x 3): the first three factors of eq. 18,
    /// `diag(l) * d d/d n * d n/d X_C`, at a point with `z_c != 0`.
    #[inline]
    pub fn project_jacobian(&self, xc: &Vector3<T>) -> SMatrix<T, 2, 3> {
        let (one, two, three) = (T::one(), cast::<T>(2.0), cast::<T>(3.0));
        let k = self.kc1;
        let inv_z = one / xc[2];
        let (nx, ny) = (xc[0] * inv_z, xc[1] * inv_z);
        let (nx2, ny2) = (nx * nx, ny * ny);
        let off = two * k * nx * ny;
        // diag(l) * distortion Jacobian.
        let ld = Matrix2::new(
            self.focal[0] * (one + three * k * nx2 + k * ny2),
            self.focal[0] * off,
            self.focal[1] * off,
            self.focal[1] * (one + k * nx2 + three * k * ny2),
        );
        // Pinhole Jacobian dn/dX_C = [[1/z, 0, -x/z^2], [0, 1/z, -y/z^2]].
        let jn =
            SMatrix::<T, 2, 3>::new(inv_z, T::zero(), -nx * inv_z, T::zero(), inv_z, -ny * inv_z);
        ld * jn
    }
}

/// `M` marks on a rigid body seen by a fixed camera (paper 002, eq. 5-10), as
/// a [`MeasurementModel<T, 6, D>`] with `D = 2 M` (see the module
/// documentation for why both appear; `D != 2 M` fails to compile).
///
/// `h(x)` is `[u_1, v_1, ..., u_M, v_M]` (px) at state `x` (eq. 2), or `None`
/// if some mark is not in front of the camera by more than
/// [`min_depth`](Self::min_depth). `H` is eq. 18 stacked over the marks
/// (px/m, px/rad); the noise is `Theta = pixel_var I` (px^2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraMarks<T: Scalar, const M: usize, const D: usize> {
    /// The camera's intrinsic parameters.
    pub intrinsics: Intrinsics<T>,
    /// Mark coordinates `X_O` in the body frame (m), eq. 6.
    pub marks: [Vector3<T>; M],
    /// Minimum depth `z_c` (m) of every mark for a measurement to exist
    /// (> 0; default [`DEFAULT_MIN_DEPTH`] = 0.05 m).
    pub min_depth: T,
    /// Variance of each pixel coordinate `sigma_p^2` (px^2): `Theta =
    /// pixel_var I_D` (default 2^2 = 4 px^2). Used as the discrete
    /// per-image covariance by [`MeasurementModel::noise`].
    pub pixel_var: T,
}

/// The paper's configuration: four marks, an 8-dimensional measurement.
pub type CameraMarks4<T> = CameraMarks<T, 4, 8>;

/// A single mark, a 2-dimensional measurement (for mark-by-mark processing or
/// when only some marks are visible).
pub type CameraMark<T> = CameraMarks<T, 1, 2>;

impl<T: Scalar, const M: usize, const D: usize> CameraMarks<T, M, D> {
    /// Compile-time check of the dimension: `D == 2 M`.
    const DIMENSION_IS_TWICE_THE_MARKS: () = assert!(
        D == 2 * M,
        "CameraMarks<T, M, D>: D must be 2 * M (two pixel coordinates per mark)"
    );

    /// A model with the given intrinsics and marks (m, body frame), the
    /// default minimum depth 0.05 m and pixel noise `2^2` px^2.
    pub fn new(intrinsics: Intrinsics<T>, marks: [Vector3<T>; M]) -> Self {
        let () = Self::DIMENSION_IS_TWICE_THE_MARKS;
        Self {
            intrinsics,
            marks,
            min_depth: cast(DEFAULT_MIN_DEPTH),
            pixel_var: cast(SIGMA_PIXEL * SIGMA_PIXEL),
        }
    }

    /// The same model with another minimum depth (m, > 0).
    pub fn with_min_depth(mut self, min_depth: T) -> Self {
        self.min_depth = min_depth;
        self
    }

    /// The same model with another pixel variance (px^2, > 0).
    pub fn with_pixel_var(mut self, pixel_var: T) -> Self {
        self.pixel_var = pixel_var;
        self
    }

    /// Camera-frame coordinates `X_C = T + R X_O` (m, eq. 7) of every mark at
    /// state `x`.
    pub fn marks_in_camera(&self, x: &SVector<T, 6>) -> [Vector3<T>; M] {
        let rot = EulerRotation::from_state(x);
        let t = Vector3::new(x[0], x[1], x[2]);
        self.marks.map(|xo| t + rot.r * xo)
    }

    /// True if every mark lies deeper than [`min_depth`](Self::min_depth) at
    /// state `x`, i.e. [`h`](MeasurementModel::h) is `Some`.
    pub fn all_visible(&self, x: &SVector<T, 6>) -> bool {
        self.marks_in_camera(x)
            .iter()
            .all(|xc| xc[2] > self.min_depth)
    }

    /// True if every parameter is finite.
    pub fn is_finite(&self) -> bool {
        self.intrinsics.focal.iter().all(|v| v.is_finite())
            && self.intrinsics.principal.iter().all(|v| v.is_finite())
            && self.intrinsics.kc1.is_finite()
            && self.marks.iter().flatten().all(|v| v.is_finite())
            && self.min_depth.is_finite()
            && self.pixel_var.is_finite()
    }
}

impl<T: Scalar> CameraMarks4<T> {
    /// The spec's \[assumed\] four marks of paper 002 (m, body frame):
    /// `(0.30, 0, 0)`, `(-0.30, 0, 0)`, `(0, 0.20, 0)`, `(0, -0.10, 0.15)`,
    /// with the paper's intrinsics (see [`Intrinsics::paper_002`]), minimum
    /// depth 0.05 m and pixel noise `Theta = 2^2 I` px^2.
    pub fn paper_002() -> Self {
        let z = T::zero();
        Self::new(
            Intrinsics::paper_002(),
            [
                Vector3::new(cast(0.30), z, z),
                Vector3::new(cast(-0.30), z, z),
                Vector3::new(z, cast(0.20), z),
                Vector3::new(z, cast(-0.10), cast(0.15)),
            ],
        )
    }
}

impl<T: Scalar, const M: usize, const D: usize> MeasurementModel<T, 6, D> for CameraMarks<T, M, D> {
    /// `[u_1, v_1, ..., u_M, v_M]` (px), eq. 5-10; `None` if any mark has
    /// `z_c <= min_depth` (or a non-finite depth). `C = dh/dx` (`D x 6`,
    /// px/m and px/rad), eq. 18 per mark with the spec's fixed
    /// `dR/dtheta`, rows `2j, 2j + 1` for mark `j`; one rotation for both.
    fn evaluate(
        &self,
        x: &SVector<T, 6>,
        mut jacobian: Option<&mut SMatrix<T, D, 6>>,
    ) -> Option<SVector<T, D>> {
        let () = Self::DIMENSION_IS_TWICE_THE_MARKS;
        let rot = EulerRotation::from_state(x);
        let t = Vector3::new(x[0], x[1], x[2]);
        let mut y = SVector::<T, D>::zeros();
        for (j, xo) in self.marks.iter().enumerate() {
            let rxo = rot.r * xo;
            let xc = t + rxo;
            // A non-finite depth (NaN) is no measurement either.
            if !xc[2].is_finite() || xc[2] <= self.min_depth {
                return None;
            }
            let p = self.intrinsics.project(&xc);
            y[2 * j] = p[0];
            y[2 * j + 1] = p[1];
            if let Some(c) = jacobian.as_deref_mut() {
                let jp = self.intrinsics.project_jacobian(&xc);
                // jp * [I3 | dR/dphi X_O | dR/dtheta X_O | dR/dpsi X_O], by
                // blocks.
                let mut block = c.fixed_view_mut::<2, 6>(2 * j, 0);
                block.fixed_view_mut::<2, 3>(0, 0).copy_from(&jp);
                block.set_column(3, &(jp * rot.d_phi(xo)));
                block.set_column(4, &(jp * rot.d_theta(xo)));
                // dR/dpsi X_O = e3 x (R X_O), reusing R X_O.
                block.set_column(5, &(jp * Vector3::new(-rxo[1], rxo[0], T::zero())));
            }
        }
        Some(y)
    }

    /// `Theta = pixel_var I_D` (px^2).
    fn noise(&self, _x: &SVector<T, 6>) -> SMatrix<T, D, D> {
        let () = Self::DIMENSION_IS_TWICE_THE_MARKS;
        SMatrix::<T, D, D>::identity() * self.pixel_var
    }
}

/// The 6-DOF random-walk motion of paper 002 (eq. 1, 11, 23), discretised
/// exactly over a step of `dt` seconds (the input).
///
/// Continuous time: `dx/dt = delta`, `delta` white with density `Q`
/// ([`q`](Self::q); units m^2/s for `tx, ty, tz`, rad^2/s for
/// `phi, theta, psi`). Over a step `dt` the state moves by the integral of
/// `delta`, a Gaussian increment `q ~ N(0, Q dt)`, so the discrete model is
/// ```text
/// x' = f(x, dt, q) = x + q,   q ~ N(0, Q_d),   Q_d = Q dt   (m^2, rad^2)
/// A = df/dx = I6,             W = df/dq = I6
/// ```
/// (equivalently `x' = x + dt delta_bar` with the step's mean velocity
/// `delta_bar ~ N(0, Q / dt)` and `W = dt I`; both give `W Q W^T = Q dt`;
/// this form has no division by `dt`, so `dt = 0` is valid and adds no
/// noise). The angle components of `f` are wrapped to (-pi, pi], and state
/// differences wrap them too. Valid for any state and any `dt >= 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RandomWalk6<T: Scalar> {
    /// Continuous-time noise density `Q` (6 x 6, symmetric PSD; m^2/s and
    /// rad^2/s on the diagonal).
    pub q: SMatrix<T, 6, 6>,
}

impl<T: Scalar> Default for RandomWalk6<T> {
    /// The paper's `Q = diag(0.1^2 x3, 0.1396^2 x3)` (eq. 23).
    fn default() -> Self {
        Self { q: paper_q() }
    }
}

impl<T: Scalar> RandomWalk6<T> {
    /// A random walk with density `Q` (see the type's documentation).
    pub fn new(q: SMatrix<T, 6, 6>) -> Self {
        Self { q }
    }

    /// A random walk with diagonal density `Q = diag(q)`.
    pub fn from_diagonal(q: &SVector<T, 6>) -> Self {
        Self {
            q: SMatrix::from_diagonal(q),
        }
    }
}

impl<T: Scalar> MotionModel<T, 6, 6> for RandomWalk6<T> {
    /// The step `dt` (s, finite, >= 0).
    type Input = T;

    /// `x + q`, angles wrapped; `A = W = I6`.
    fn evaluate(
        &self,
        x: &SVector<T, 6>,
        _dt: &T,
        q: &SVector<T, 6>,
        jacobians: Option<&mut MotionJacobians<T, 6, 6>>,
    ) -> SVector<T, 6> {
        if let Some(j) = jacobians {
            j.a = SMatrix::identity();
            j.w = SMatrix::identity();
        }
        let mut y = x + q;
        for i in 3..6 {
            y[i] = wrap_angle(y[i]);
        }
        y
    }

    /// `Q_d = Q dt` (m^2, rad^2).
    fn noise_cov(&self, dt: &T) -> SMatrix<T, 6, 6> {
        self.q * *dt
    }

    fn input_is_finite(&self, dt: &T) -> bool {
        dt.is_finite()
    }

    fn state_residual(&self, a: &SVector<T, 6>, b: &SVector<T, 6>) -> SVector<T, 6> {
        let mut d = a - b;
        for i in 3..6 {
            d[i] = wrap_angle(d[i]);
        }
        d
    }
}
