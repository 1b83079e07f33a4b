//! The built-in models as Python classes (`locus.DiffDrive`,
//! `locus.Unicycle`, `locus.SkidSteer`; `locus.RangeBearing`,
//! `locus.IrPair`, `locus.LaserRange`): each with its function and its
//! Jacobians (`f` and `jacobians` of a motion, `h` and `jacobian` of a
//! sensor), so a notebook can plot them, and each usable in a
//! `locus.Filter`. The equations are `locus_models`' (paper 001's
//! differential drive and IR pair, paper 000's skid steer and laser, the
//! unicycle and range-bearing of recorded logs).

use std::collections::HashMap;

use locus_core::nalgebra::{SMatrix, SVector, Vector2, Vector3};
use locus_core::{MeasurementModel, MotionModel};
use locus_models::laser_wall::{LaserMount, LaserRange as LaserModel, Segment};
use locus_models::{
    AxisWall, DiffDrive as DiffDriveModel, IrPair as IrPairGeometry, IrPairObservation,
    RangeBearing as RangeBearingModel, SkidSteer as SkidSteerModel, TreadSpeeds,
    Unicycle as UnicycleModel, Velocities, WheelTravel,
};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use crate::arrays::{self, column, dense};
use crate::error::value_error;

/// A number that must be finite and > 0, named.
pub fn positive(name: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(value_error(name, format!("{v} is not a finite number > 0")))
    }
}

/// A number that must be finite and >= 0, named.
fn non_negative(name: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(value_error(
            name,
            format!("{v} is not a finite number >= 0"),
        ))
    }
}

/// A number that must be finite, named.
fn finite(name: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(value_error(name, format!("{v} is not finite")))
    }
}

/// A motion model of a `locus.Filter`, with its input's meaning.
#[derive(Clone, Copy)]
pub enum Motion {
    /// Paper 001: wheel travels `(d1, d2)` [m], right wheel first.
    DiffDrive(DiffDriveModel<f64>),
    /// Velocities `(v [m/s], omega [rad/s], dt [s])`.
    Unicycle(UnicycleModel<f64>),
    /// Paper 000: tread speeds `(v_l, v_r [m/s], dt [s])`.
    SkidSteer(SkidSteerModel<f64>),
}

impl Motion {
    /// The input's numbers, named in errors.
    pub const fn input_len(&self) -> usize {
        match self {
            Self::DiffDrive(_) => DiffDriveModel::<f64>::LEN,
            Self::Unicycle(_) => UnicycleModel::<f64>::LEN,
            Self::SkidSteer(_) => SkidSteerModel::<f64>::LEN,
        }
    }

    /// `f(x, u, 0)` and its Jacobians `A = df/dx`, `W = df/dq`.
    pub fn linearize(
        &self,
        x: &SVector<f64, 3>,
        u: &[f64],
    ) -> (SVector<f64, 3>, SMatrix<f64, 3, 3>, SMatrix<f64, 3, 2>) {
        match self {
            Self::DiffDrive(m) => m.linearize(x, &DiffDriveModel::input(u)),
            Self::Unicycle(m) => m.linearize(x, &UnicycleModel::input(u)),
            Self::SkidSteer(m) => m.linearize(x, &SkidSteerModel::input(u)),
        }
    }

    /// The process noise `Q` of the input `u`.
    pub fn noise(&self, u: &[f64]) -> SMatrix<f64, 2, 2> {
        match self {
            Self::DiffDrive(m) => m.noise_cov(&DiffDriveModel::input(u)),
            Self::Unicycle(m) => m.noise_cov(&UnicycleModel::input(u)),
            Self::SkidSteer(m) => m.noise_cov(&SkidSteerModel::input(u)),
        }
    }

    /// One prediction of `belief` by `ekf` (inlined into the batch run's
    /// loop: a call per step costs as much as the step).
    #[inline(always)]
    pub fn predict(
        &self,
        ekf: &locus_core::Ekf<f64>,
        belief: &locus_core::Belief<f64, 3>,
        u: &[f64],
    ) -> Result<locus_core::Belief<f64, 3>, locus_core::Error> {
        match self {
            Self::DiffDrive(m) => ekf.predict(belief, m, &DiffDriveModel::input(u)),
            Self::Unicycle(m) => ekf.predict(belief, m, &UnicycleModel::input(u)),
            Self::SkidSteer(m) => ekf.predict(belief, m, &SkidSteerModel::input(u)),
        }
    }
}

/// A motion model whose input Python gives as a row of numbers (see
/// [`Motion`]): the one place each model's row becomes its input.
pub trait Row: MotionModel<f64, 3, 2> {
    /// The row's length.
    const LEN: usize;
    /// The input of the row `u` (`LEN` numbers).
    fn input(u: &[f64]) -> Self::Input;
}

impl Row for DiffDriveModel<f64> {
    const LEN: usize = 2;
    #[inline(always)]
    fn input(u: &[f64]) -> WheelTravel<f64> {
        WheelTravel { d1: u[0], d2: u[1] }
    }
}

impl Row for UnicycleModel<f64> {
    const LEN: usize = 3;
    #[inline(always)]
    fn input(u: &[f64]) -> Velocities<f64> {
        Velocities {
            v: u[0],
            omega: u[1],
            dt: u[2],
        }
    }
}

impl Row for SkidSteerModel<f64> {
    const LEN: usize = 3;
    #[inline(always)]
    fn input(u: &[f64]) -> TreadSpeeds<f64> {
        TreadSpeeds::new(u[0], u[1], u[2])
    }
}

/// Shared methods of the motion classes.
macro_rules! motion_methods {
    ($t:ty, $($new:tt)*) => {
        #[pymethods]
        impl $t {
            $($new)*

            /// The next state `f(x, u)` (noise-free), x = (x [m], y [m], theta [rad]).
            fn f<'py>(
                &self,
                py: Python<'py>,
                x: &Bound<'py, PyAny>,
                u: &Bound<'py, PyAny>,
            ) -> PyResult<Bound<'py, PyArray1<f64>>> {
                let x = Vector3::from(arrays::fixed::<3>("x", x)?);
                let u = crate::filter::input3(&self.0, u)?;
                Ok(column(py, &self.0.linearize(&x, &u).0))
            }

            /// The Jacobians `(A, W)`: `A = df/dx` (3 x 3) and `W = df/dq`
            /// (3 x 2, q the input noise), at `x` and `u`.
            fn jacobians<'py>(
                &self,
                py: Python<'py>,
                x: &Bound<'py, PyAny>,
                u: &Bound<'py, PyAny>,
            ) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
                let x = Vector3::from(arrays::fixed::<3>("x", x)?);
                let u = crate::filter::input3(&self.0, u)?;
                let (_, a, w) = self.0.linearize(&x, &u);
                Ok((dense(py, &a), dense(py, &w)))
            }

            /// The input noise's covariance `Q` (2 x 2) for the input `u`.
            fn noise<'py>(
                &self,
                py: Python<'py>,
                u: &Bound<'py, PyAny>,
            ) -> PyResult<Bound<'py, PyArray2<f64>>> {
                let u = crate::filter::input3(&self.0, u)?;
                Ok(dense(py, &self.0.noise(&u)))
            }
        }
    };
}

/// Paper 001's differential drive (eqs. 8 to 10): the input is the wheel
/// travels `u = (d1, d2)` [m] in the step, right wheel first.
#[pyclass(frozen, module = "locus")]
#[derive(Clone)]
pub struct DiffDrive(pub Motion);

motion_methods!(
    DiffDrive,
    /// `wheelbase` [m]; `q11` the variance of the travelled distance
    /// [m^2], `q22` of the heading change [rad^2], per step.
    #[new]
    fn new(wheelbase: f64, q11: f64, q22: f64) -> PyResult<Self> {
        Ok(Self(Motion::DiffDrive(DiffDriveModel::new(
            positive("wheelbase", wheelbase)?,
            non_negative("q11", q11)?,
            non_negative("q22", q22)?,
        ))))
    }
);

/// The unicycle of recorded logs: the input is `u = (v [m/s], omega
/// [rad/s], dt [s])`, held over the step (exact arc).
#[pyclass(frozen, module = "locus")]
#[derive(Clone)]
pub struct Unicycle(pub Motion);

motion_methods!(
    Unicycle,
    /// `var_v` [m^2/s^2] and `var_omega` [rad^2/s^2]: the variances of
    /// the speed and turn rate over a step.
    #[new]
    fn new(var_v: f64, var_omega: f64) -> PyResult<Self> {
        Ok(Self(Motion::Unicycle(UnicycleModel::new(
            non_negative("var_v", var_v)?,
            non_negative("var_omega", var_omega)?,
        ))))
    }
);

/// Paper 000's skid steer: the input is the tread speeds `u = (v_l, v_r
/// [m/s], dt [s])`.
#[pyclass(frozen, module = "locus")]
#[derive(Clone)]
pub struct SkidSteer(pub Motion);

motion_methods!(
    SkidSteer,
    /// `track_width` [m]; `var_vl`, `var_vr` [m^2/s^2]: the variances of
    /// the tread speeds.
    #[new]
    fn new(track_width: f64, var_vl: f64, var_vr: f64) -> PyResult<Self> {
        Ok(Self(Motion::SkidSteer(SkidSteerModel::new(
            positive("track_width", track_width)?,
            non_negative("var_vl", var_vl)?,
            non_negative("var_vr", var_vr)?,
        ))))
    }
);

/// A sensor of a `locus.Filter`.
#[derive(Clone)]
pub enum Sensor {
    /// Range and bearing to landmarks of known position, by id.
    RangeBearing {
        /// The model (its landmark set per update).
        model: RangeBearingModel<f64>,
        /// Landmark positions by id, m.
        landmarks: HashMap<u32, [f64; 2]>,
    },
    /// Paper 001's IR pair against the square arena's walls.
    IrPair {
        /// The pair's geometry.
        pair: IrPairGeometry<f64>,
        /// The walls' distance from the centre `Lw`, m.
        arena: f64,
        /// Variances of the two readings, m^2.
        r: [f64; 2],
    },
    /// Paper 000's laser range finder against wall segments.
    Laser {
        /// The mount.
        mount: LaserMount<f64>,
        /// The walls.
        segments: Vec<Segment<f64>>,
        /// Variance of a range, m^2.
        var_range: f64,
    },
}

/// The arena's wall of index `index` (0 `x+`, 1 `x-`, 2 `y+`, 3 `y-`)
/// at `arena` metres from the centre.
#[inline]
pub fn wall(index: i64, arena: f64) -> Option<AxisWall<f64>> {
    Some(match index {
        0 => AxisWall::x_plus(arena),
        1 => AxisWall::x_minus(arena),
        2 => AxisWall::y_plus(arena),
        3 => AxisWall::y_minus(arena),
        _ => return None,
    })
}

/// Paper 001's IR pair correction: the observation from the readings
/// `z = (ds1, ds2)` of the wall `at` (see [`wall`]).
#[inline(always)]
pub fn ir_correct(
    ekf: &locus_core::Ekf<f64>,
    belief: &locus_core::Belief<f64, 3>,
    (pair, arena, r): (&IrPairGeometry<f64>, f64, &[f64; 2]),
    z: &[f64],
    at: i64,
) -> Result<Corrected, String> {
    let wall =
        wall(at, arena).ok_or_else(|| format!("wall {at} is not 0 to 3 (x+, x-, y+, y-)"))?;
    let m = IrPairObservation {
        pair: *pair,
        wall,
        ds1: z[0],
        ds2: z[1],
        r11: r[0],
        r22: r[1],
    };
    Ok(ekf
        .correct(belief, &m, &m.z())
        .map(|c| (c.belief, c.nis, c.applied)))
}

/// A wall's index from its name or index.
pub fn wall_index(at: &Bound<'_, PyAny>) -> PyResult<i64> {
    if let Ok(i) = at.extract::<i64>() {
        return if (0..4).contains(&i) {
            Ok(i)
        } else {
            Err(value_error(
                "at",
                format!("wall {i} is not 0 to 3 (x+, x-, y+, y-)"),
            ))
        };
    }
    let name: String = at.extract().map_err(|_| {
        value_error(
            "at",
            "expected a wall: \"x+\", \"x-\", \"y+\", \"y-\" or 0 to 3",
        )
    })?;
    match name.as_str() {
        "x+" => Ok(0),
        "x-" => Ok(1),
        "y+" => Ok(2),
        "y-" => Ok(3),
        other => Err(value_error(
            "at",
            format!("{other:?} is not a wall: \"x+\", \"x-\", \"y+\", \"y-\""),
        )),
    }
}

/// A correction's posterior, NIS and whether it was applied, or the
/// filter's error (the reading is unusable).
pub type Corrected = Result<(locus_core::Belief<f64, 3>, f64, bool), locus_core::Error>;

/// The outcome of one measurement model evaluated: `z_hat` and `H`, or
/// `None` when the model predicts no measurement there.
pub type Predicted = Option<(Vec<f64>, Vec<f64>, usize)>;

impl Sensor {
    /// The measurement's dimension.
    pub const fn dim(&self) -> usize {
        match self {
            Self::RangeBearing { .. } | Self::IrPair { .. } => 2,
            Self::Laser { .. } => 1,
        }
    }

    /// The landmark `id`'s position.
    fn landmark(landmarks: &HashMap<u32, [f64; 2]>, id: i64) -> Result<Vector2<f64>, String> {
        u32::try_from(id)
            .ok()
            .and_then(|i| landmarks.get(&i))
            .map(|p| Vector2::new(p[0], p[1]))
            .ok_or_else(|| format!("landmark {id} is not in the map"))
    }

    /// `h(x)` and `H` for what `at` names (a landmark id or a wall index).
    pub fn predict(&self, x: &SVector<f64, 3>, at: i64) -> Result<Predicted, String> {
        fn pack<const M: usize>(p: Option<(SVector<f64, M>, SMatrix<f64, M, 3>)>) -> Predicted {
            p.map(|(z, h)| (z.as_slice().to_vec(), h.transpose().as_slice().to_vec(), M))
        }
        Ok(match self {
            Self::RangeBearing { model, landmarks } => {
                let m = model.with_landmark(Self::landmark(landmarks, at)?);
                pack(m.linearize(x))
            }
            Self::IrPair { pair, arena, r } => {
                let w = wall(at, *arena).ok_or_else(|| format!("wall {at} is not 0 to 3"))?;
                let m = IrPairObservation {
                    pair: *pair,
                    wall: w,
                    ds1: 0.0,
                    ds2: 0.0,
                    r11: r[0],
                    r22: r[1],
                };
                pack(m.linearize(x))
            }
            Self::Laser {
                mount,
                segments,
                var_range,
            } => pack(LaserModel::new(*mount, segments, *var_range).linearize(x)),
        })
    }

    /// One correction of `belief` by `ekf` with the reading `z` of what
    /// `at` names. For the IR pair `z` is the two readings `(ds1, ds2)` [m]
    /// (paper 001's observation is computed from them); for landmarks
    /// `(range [m], bearing [rad])`; for the laser `(range [m],)`.
    #[inline(always)]
    pub fn correct(
        &self,
        ekf: &locus_core::Ekf<f64>,
        belief: &locus_core::Belief<f64, 3>,
        z: &[f64],
        at: i64,
    ) -> Result<Corrected, String> {
        let out = |c: Result<locus_core::Correction<f64, 3, 2>, locus_core::Error>| {
            c.map(|c| (c.belief, c.nis, c.applied))
        };
        Ok(match self {
            Self::RangeBearing { model, landmarks } => {
                let m = model.with_landmark(Self::landmark(landmarks, at)?);
                out(ekf.correct(belief, &m, &Vector2::new(z[0], z[1])))
            }
            Self::IrPair { pair, arena, r } => {
                return ir_correct(ekf, belief, (pair, *arena, r), z, at);
            }
            Self::Laser {
                mount,
                segments,
                var_range,
            } => {
                let m = LaserModel::new(*mount, segments, *var_range);
                ekf.correct(belief, &m, &SVector::<f64, 1>::new(z[0]))
                    .map(|c| (c.belief, c.nis, c.applied))
            }
        })
    }

    /// What `at` names, from Python: a landmark id, a wall, or nothing.
    pub fn at(&self, at: Option<&Bound<'_, PyAny>>) -> PyResult<i64> {
        match (self, at) {
            (Self::RangeBearing { .. }, Some(a)) => a
                .extract()
                .map_err(|_| value_error("at", "expected a landmark id (an integer)")),
            (Self::RangeBearing { .. }, None) => Err(value_error("at", "give the landmark's id")),
            (Self::IrPair { .. }, Some(a)) => wall_index(a),
            (Self::IrPair { .. }, None) => Err(value_error(
                "at",
                "give the wall (\"x+\", \"x-\", \"y+\", \"y-\")",
            )),
            (Self::Laser { .. }, _) => Ok(0),
        }
    }
}

/// Shared methods of the sensor classes.
macro_rules! sensor_methods {
    ($t:ty, $($new:tt)*) => {
        #[pymethods]
        impl $t {
            $($new)*

            /// The predicted measurement `h(x)` of what `at` names (a
            /// landmark id, a wall; nothing for the laser); `None` where
            /// the model predicts none (a laser ray that hits no wall).
            #[pyo3(signature = (x, at=None))]
            fn h<'py>(
                &self,
                py: Python<'py>,
                x: &Bound<'py, PyAny>,
                at: Option<&Bound<'py, PyAny>>,
            ) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
                let x = Vector3::from(arrays::fixed::<3>("x", x)?);
                let at = self.0.at(at)?;
                let p = self.0.predict(&x, at).map_err(|e| value_error("at", e))?;
                Ok(p.map(|(z, _, _)| arrays::vector(py, z)))
            }

            /// The Jacobian `H = dh/dx` (M x 3) at `x`, as `h`.
            #[pyo3(signature = (x, at=None))]
            fn jacobian<'py>(
                &self,
                py: Python<'py>,
                x: &Bound<'py, PyAny>,
                at: Option<&Bound<'py, PyAny>>,
            ) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
                let x = Vector3::from(arrays::fixed::<3>("x", x)?);
                let at = self.0.at(at)?;
                let p = self.0.predict(&x, at).map_err(|e| value_error("at", e))?;
                Ok(p.map(|(_, h, _)| arrays::matrix(py, h, 3)))
            }
        }
    };
}

/// Range and bearing to landmarks of known position (`z = (range [m],
/// bearing [rad])`, the bearing from the sensor's x axis).
#[pyclass(frozen, module = "locus")]
#[derive(Clone)]
pub struct RangeBearing(pub Sensor);

sensor_methods!(
    RangeBearing,
    /// `landmarks`: (K, 3) rows `id, x [m], y [m]`; `sigma_range` [m] and
    /// `sigma_bearing` [rad], the readings' standard deviations; `sensor`
    /// the sensor's position on the robot `(x forward, y left)` [m].
    #[new]
    #[pyo3(signature = (landmarks, sigma_range, sigma_bearing, sensor=(0.0, 0.0)))]
    fn new(
        landmarks: &Bound<'_, PyAny>,
        sigma_range: f64,
        sigma_bearing: f64,
        sensor: (f64, f64),
    ) -> PyResult<Self> {
        let rows = arrays::rows("landmarks", landmarks, 3, &[])?;
        let mut map = HashMap::new();
        for (i, r) in rows.iter().enumerate() {
            if !(r[0] >= 0.0 && r[0].fract() == 0.0 && r[0] <= f64::from(u32::MAX)) {
                return Err(value_error(
                    "landmarks",
                    format!("row {i}: the id {} is not a whole number >= 0", r[0]),
                ));
            }
            #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
            if map.insert(r[0] as u32, [r[1], r[2]]).is_some() {
                return Err(value_error(
                    "landmarks",
                    format!("row {i}: the id {} is repeated", r[0]),
                ));
            }
        }
        let sensor = Vector2::new(finite("sensor", sensor.0)?, finite("sensor", sensor.1)?);
        Ok(Self(Sensor::RangeBearing {
            model: RangeBearingModel::new(
                Vector2::zeros(),
                sensor,
                positive("sigma_range", sigma_range)?,
                positive("sigma_bearing", sigma_bearing)?,
            ),
            landmarks: map,
        }))
    }
);

/// Paper 001's pair of IR sensors against the walls of the square arena
/// (eqs. 11 to 16): `z = (ds1, ds2)`, the front and rear readings [m];
/// `at` the wall, `"x+"`, `"x-"`, `"y+"` or `"y-"` (or 0 to 3). `h(x)` is
/// the observation `(wall coordinate across [m], heading [rad])`.
#[pyclass(frozen, module = "locus")]
#[derive(Clone)]
pub struct IrPair(pub Sensor);

sensor_methods!(
    IrPair,
    /// `spacing` `L` between the sensors [m]; `arena` `Lw`, the walls at
    /// x, y = +-Lw [m]; `r11`, `r22` the readings' variances [m^2];
    /// `lateral` `e` (to the right) and `forward` `c` offsets of the pair
    /// [m].
    #[new]
    #[pyo3(signature = (spacing, arena, r11, r22, lateral=0.0, forward=0.0))]
    fn new(
        spacing: f64,
        arena: f64,
        r11: f64,
        r22: f64,
        lateral: f64,
        forward: f64,
    ) -> PyResult<Self> {
        Ok(Self(Sensor::IrPair {
            pair: IrPairGeometry {
                spacing: positive("spacing", spacing)?,
                lateral_offset: finite("lateral", lateral)?,
                forward_offset: finite("forward", forward)?,
            },
            arena: positive("arena", arena)?,
            r: [positive("r11", r11)?, positive("r22", r22)?],
        }))
    }
);

/// Paper 000's laser range finder against wall segments: `z = (range
/// [m],)`, the distance along the beam to the nearest wall.
#[pyclass(frozen, module = "locus")]
#[derive(Clone)]
pub struct LaserRange(pub Sensor);

sensor_methods!(
    LaserRange,
    /// `segments`: (K, 4) rows `x1, y1, x2, y2` [m]; `var_range` [m^2];
    /// `mount` the sensor on the robot `(x [m], y [m], beta [rad])`.
    #[new]
    #[pyo3(signature = (segments, var_range, mount=(0.0, 0.0, 0.0)))]
    fn new(segments: &Bound<'_, PyAny>, var_range: f64, mount: (f64, f64, f64)) -> PyResult<Self> {
        let rows = arrays::rows("segments", segments, 4, &[])?;
        if rows.is_empty() {
            return Err(value_error("segments", "give at least one wall"));
        }
        Ok(Self(Sensor::Laser {
            mount: LaserMount::new(
                finite("mount", mount.0)?,
                finite("mount", mount.1)?,
                finite("mount", mount.2)?,
            ),
            segments: rows
                .iter()
                .map(|r| Segment::new([r[0], r[1]], [r[2], r[3]]))
                .collect(),
            var_range: positive("var_range", var_range)?,
        }))
    }
);
