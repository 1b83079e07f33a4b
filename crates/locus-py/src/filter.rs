//! `locus.Filter`: an EKF over a built-in motion model and, optionally,
//! a sensor (`crate::models`). One step at a time (`predict`, `update`,
//! `step`) for teaching, or a whole run at once (`run`) that stays in
//! Rust. The filter is Locus's stateless [`Ekf`] over a belief value the
//! object holds; a step that fails (a NaN, a covariance that is not
//! positive definite) raises and leaves the belief as it was.

use alloc::borrow::Cow;
use locus_core::nalgebra::{Matrix3, Vector3};
use locus_core::{Belief, ChiSquareGate, CovarianceUpdate, Ekf};

use numpy::{
    PyArray1, PyArray2, PyArray3, PyArrayDyn, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyReadwriteArrayDyn, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{self, column, dense};
use crate::error::{LocusError, value_error};
use crate::models::{
    Corrected, DiffDrive, IrPair, LaserRange, Motion, RangeBearing, Row, Sensor, SkidSteer,
    Unicycle, ir_correct,
};
use locus_models::IrPair as IrPairGeometry;

/// An EKF of a planar pose `(x [m], y [m], theta [rad])`.
#[pyclass(module = "locus")]
pub struct Filter {
    motion: Motion,
    sensor: Option<Sensor>,
    ekf: Ekf<f64>,
    belief: Belief<f64, 3>,
}

/// The motion model a Python object holds.
fn motion_of(m: &Bound<'_, PyAny>) -> PyResult<Motion> {
    if let Ok(d) = m.cast::<DiffDrive>() {
        Ok(d.get().0)
    } else if let Ok(u) = m.cast::<Unicycle>() {
        Ok(u.get().0)
    } else if let Ok(s) = m.cast::<SkidSteer>() {
        Ok(s.get().0)
    } else {
        Err(value_error(
            "motion",
            "expected locus.DiffDrive, locus.Unicycle or locus.SkidSteer",
        ))
    }
}

/// The sensor model a Python object holds.
fn sensor_of(s: &Bound<'_, PyAny>) -> PyResult<Sensor> {
    if let Ok(r) = s.cast::<RangeBearing>() {
        Ok(r.get().0.clone())
    } else if let Ok(i) = s.cast::<IrPair>() {
        Ok(i.get().0.clone())
    } else if let Ok(l) = s.cast::<LaserRange>() {
        Ok(l.get().0.clone())
    } else {
        Err(value_error(
            "sensor",
            "expected locus.RangeBearing, locus.IrPair or locus.LaserRange",
        ))
    }
}

fn filter_error(what: &str, e: &locus_core::Error) -> PyErr {
    LocusError::new_err(format!("{what}: {e}; the belief is unchanged"))
}

impl Filter {
    fn sensor(&self) -> PyResult<&Sensor> {
        self.sensor.as_ref().ok_or_else(|| {
            value_error(
                "sensor",
                "this filter has no sensor: give one to locus.Filter",
            )
        })
    }

    fn reading(&self, z: &Bound<'_, PyAny>) -> PyResult<[f64; 2]> {
        Ok(match self.sensor()?.dim() {
            1 => {
                let v = if let Ok(x) = z.extract::<f64>() {
                    x
                } else {
                    arrays::fixed::<1>("z", z)?[0]
                };
                if !v.is_finite() {
                    return Err(value_error("z", format!("{v} is not finite")));
                }
                [v, 0.0]
            }
            _ => arrays::fixed::<2>("z", z)?,
        })
    }

    fn do_update(&mut self, z: &[f64], at: i64) -> PyResult<(f64, bool)> {
        let sensor = self.sensor()?;
        match sensor.correct(&self.ekf, &self.belief, z, at) {
            Err(why) => Err(value_error("at", why)),
            Ok(Err(e)) => Err(filter_error("update", &e)),
            Ok(Ok((belief, nis, applied))) => {
                self.belief = belief;
                Ok((nis, applied))
            }
        }
    }
}

#[pymethods]
impl Filter {
    /// A filter of `motion` (locus.DiffDrive, locus.Unicycle,
    /// locus.SkidSteer) and optionally `sensor` (locus.RangeBearing,
    /// locus.IrPair, locus.LaserRange), starting from the mean `x0`
    /// `(x [m], y [m], theta [rad])` and covariance `P0` (3 x 3). `gate`, a
    /// confidence in (0, 1), rejects readings whose NIS is beyond it
    /// (chi-square); `None` applies every reading. The covariance update
    /// is Joseph's form.
    #[new]
    #[pyo3(signature = (motion, sensor=None, x0=(0.0, 0.0, 0.0), P0=None, gate=None))]
    #[allow(non_snake_case)]
    fn new(
        motion: &Bound<'_, PyAny>,
        sensor: Option<&Bound<'_, PyAny>>,
        x0: (f64, f64, f64),
        P0: Option<&Bound<'_, PyAny>>,
        gate: Option<f64>,
    ) -> PyResult<Self> {
        let x = Vector3::new(x0.0, x0.1, x0.2);
        if x.iter().any(|v| !v.is_finite()) {
            return Err(value_error("x0", "every entry must be finite"));
        }
        let p = match P0 {
            Some(p) => Matrix3::from(arrays::square::<3>("P0", p)?).transpose(),
            None => Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 1e-4)),
        };
        let belief = Belief::new(x, p);
        belief
            .validate()
            .map_err(|e| value_error("P0", format!("{e}")))?;
        let mut ekf = Ekf::new(CovarianceUpdate::Joseph);
        if let Some(g) = gate {
            ekf = ekf
                .with_gate(ChiSquareGate::new(g).map_err(|e| value_error("gate", format!("{e}")))?);
        }
        Ok(Self {
            motion: motion_of(motion)?,
            sensor: sensor.map(sensor_of).transpose()?,
            ekf,
            belief,
        })
    }

    /// The motion model; set it to change the model between steps (a
    /// process noise that varies with the step, say).
    #[setter]
    fn set_motion(&mut self, motion: &Bound<'_, PyAny>) -> PyResult<()> {
        self.motion = motion_of(motion)?;
        Ok(())
    }

    /// The sensor model; set it to change the model between steps.
    #[setter]
    fn set_sensor(&mut self, sensor: &Bound<'_, PyAny>) -> PyResult<()> {
        self.sensor = Some(sensor_of(sensor)?);
        Ok(())
    }

    /// The mean `(x [m], y [m], theta [rad])`.
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        column(py, &self.belief.x)
    }

    /// The covariance (3 x 3) [m^2, m rad, rad^2].
    #[getter]
    #[allow(non_snake_case)]
    fn P<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        dense(py, &self.belief.p)
    }

    /// Predicts over one step with the motion's input `u` (see the motion
    /// model); raises `LocusError` (the belief unchanged) if it fails.
    fn predict(&mut self, u: &Bound<'_, PyAny>) -> PyResult<()> {
        let u = input3(&self.motion, u)?;
        self.belief = self
            .motion
            .predict(&self.ekf, &self.belief, &u)
            .map_err(|e| filter_error("predict", &e))?;
        Ok(())
    }

    /// Corrects with the reading `z` of what `at` names (a landmark id; a
    /// wall, "x+", "x-", "y+", "y-"; nothing for the laser). Returns
    /// `(nis, applied)`: the normalised innovation squared, and whether
    /// the gate let the reading in.
    #[pyo3(signature = (z, at=None))]
    fn update(
        &mut self,
        z: &Bound<'_, PyAny>,
        at: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<(f64, bool)> {
        let z = self.reading(z)?;
        let at = self.sensor()?.at(at)?;
        self.do_update(&z, at)
    }

    /// `predict(u)`, then `update(z, at)` if `z` is given. Returns the
    /// update's NIS, or None without a reading.
    #[pyo3(signature = (u, z=None, at=None))]
    fn step(
        &mut self,
        u: &Bound<'_, PyAny>,
        z: Option<&Bound<'_, PyAny>>,
        at: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Option<f64>> {
        let u = input3(&self.motion, u)?;
        let reading = match z {
            Some(z) => Some((self.reading(z)?, self.sensor()?.at(at)?)),
            None => None,
        };
        let before = self.belief;
        self.belief = self
            .motion
            .predict(&self.ekf, &self.belief, &u)
            .map_err(|e| filter_error("predict", &e))?;
        match reading {
            None => Ok(None),
            Some((z, at)) => match self.do_update(&z, at) {
                Ok((nis, _)) => Ok(Some(nis)),
                Err(e) => {
                    self.belief = before;
                    Err(e)
                }
            },
        }
    }

    /// Runs `N` steps in Rust: `u` (N, k) the inputs; `z` (N, m) the
    /// readings, a row of NaN for a step without one; `at` (N,) what each
    /// reading is of (landmark ids, wall indices 0 to 3 for x+, x-, y+,
    /// y-; not needed for the laser). Returns a dict of `poses` (N, 3),
    /// `covariances` (N, 3, 3), `nis` (N,; NaN without a reading) and
    /// `applied` (N,; 0 or 1) after each step; with `out`, such a dict of
    /// arrays of those shapes (an earlier run's), they are written in place
    /// and returned (no new memory: a long run's results cost the kernel
    /// about as much to map as the filter to compute). The filter's belief
    /// becomes the last; a step that fails raises naming it, the belief
    /// unchanged. The GIL is released; Ctrl-C stops the run between
    /// chunks of 2^16 steps.
    #[pyo3(signature = (u, z=None, at=None, out=None))]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        u: PyReadonlyArray2<'py, f64>,
        z: Option<PyReadonlyArray2<'py, f64>>,
        at: Option<PyReadonlyArray1<'py, i64>>,
        out: Option<Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let k = self.motion.input_len();
        let uv = u.as_array();
        if uv.ncols() != k {
            return Err(value_error(
                "u",
                format!(
                    "expected shape (N, {k}), got ({}, {})",
                    uv.nrows(),
                    uv.ncols()
                ),
            ));
        }
        let n = uv.nrows();
        let inputs: Cow<'_, [f64]> = match u.as_slice() {
            Ok(s) => Cow::Borrowed(s),
            Err(_) => Cow::Owned(uv.iter().copied().collect()),
        };
        let m = self.sensor.as_ref().map_or(0, Sensor::dim);
        let readings: Option<Cow<'_, [f64]>> = match &z {
            Some(z) => {
                self.sensor()?;
                let zv = z.as_array();
                if zv.dim() != (n, m) {
                    return Err(value_error(
                        "z",
                        format!(
                            "expected shape ({n}, {m}), got ({}, {})",
                            zv.nrows(),
                            zv.ncols()
                        ),
                    ));
                }
                Some(match z.as_slice() {
                    Ok(s) => Cow::Borrowed(s),
                    Err(_) => Cow::Owned(zv.iter().copied().collect()),
                })
            }
            None => None,
        };
        let targets: Option<Cow<'_, [i64]>> = match &at {
            Some(a) => {
                let av = a.as_array();
                if av.len() != n {
                    return Err(value_error(
                        "at",
                        format!("expected shape ({n},), got ({},)", av.len()),
                    ));
                }
                Some(match a.as_slice() {
                    Ok(s) => Cow::Borrowed(s),
                    Err(_) => Cow::Owned(av.iter().copied().collect()),
                })
            }
            None => None,
        };
        if readings.is_some()
            && targets.is_none()
            && !matches!(self.sensor, Some(Sensor::Laser { .. }))
        {
            return Err(value_error(
                "at",
                "give what each reading is of (landmark ids or walls)",
            ));
        }
        let d = match out {
            Some(d) => d,
            None => {
                let d = PyDict::new(py);
                d.set_item("poses", PyArray2::<f64>::zeros(py, [n, 3], false))?;
                d.set_item("covariances", PyArray3::<f64>::zeros(py, [n, 3, 3], false))?;
                d.set_item("nis", PyArray1::<f64>::zeros(py, [n], false))?;
                d.set_item("applied", PyArray1::<f64>::zeros(py, [n], false))?;
                d
            }
        };
        let target = |name: &str, shape: &[usize]| -> PyResult<Bound<'py, PyUntypedArray>> {
            let a = d
                .get_item(name)?
                .ok_or_else(|| value_error("out", format!("no array {name:?}")))?;
            let a = a
                .cast_into::<PyUntypedArray>()
                .map_err(|_| value_error("out", format!("{name} is not a numpy array")))?;
            if a.shape() != shape {
                return Err(value_error(
                    "out",
                    format!("{name}: expected shape {shape:?}, got {:?}", a.shape()),
                ));
            }
            Ok(a)
        };
        let writable = |a: Bound<'py, PyUntypedArray>,
                        name: &str|
         -> PyResult<PyReadwriteArrayDyn<'py, f64>> {
            let a = a
                .cast_into::<PyArrayDyn<f64>>()
                .map_err(|_| value_error("out", format!("{name} is not an array of float64")))?;
            a.try_readwrite()
                .map_err(|_| value_error("out", format!("{name} is not writable")))
        };
        let mut poses = writable(target("poses", &[n, 3])?, "poses")?;
        let mut covs = writable(target("covariances", &[n, 3, 3])?, "covariances")?;
        let mut nis = writable(target("nis", &[n])?, "nis")?;
        let mut applied = writable(target("applied", &[n])?, "applied")?;
        let contiguous = |name: &str| value_error("out", format!("{name} is not C-contiguous"));
        let (poses, covs, nis, applied) = (
            poses.as_slice_mut().map_err(|_| contiguous("poses"))?,
            covs.as_slice_mut().map_err(|_| contiguous("covariances"))?,
            nis.as_slice_mut().map_err(|_| contiguous("nis"))?,
            applied.as_slice_mut().map_err(|_| contiguous("applied"))?,
        );
        let steps = Steps {
            motion: &self.motion,
            sensor: self.sensor.as_ref(),
            ekf: &self.ekf,
            inputs: &inputs,
            readings: readings.as_deref(),
            targets: targets.as_deref(),
        };
        let mut belief = self.belief;
        let mut start = 0;
        while start < n {
            let end = (start + CHUNK).min(n);
            let out = Out {
                poses: &mut poses[3 * start..3 * end],
                covs: &mut covs[9 * start..9 * end],
                nis: &mut nis[start..end],
                applied: &mut applied[start..end],
            };
            belief = py
                .detach(|| steps.run(start..end, belief, out))
                .map_err(|e| LocusError::new_err(format!("{e}; the belief is unchanged")))?;
            py.check_signals()?;
            start = end;
        }
        self.belief = belief;
        Ok(d)
    }
}

/// Steps a batch run takes between checks for Ctrl-C.
const CHUNK: usize = 1 << 16;

/// A batch run's inputs, flat (row-major).
struct Steps<'a> {
    motion: &'a Motion,
    sensor: Option<&'a Sensor>,
    ekf: &'a Ekf<f64>,
    inputs: &'a [f64],
    readings: Option<&'a [f64]>,
    targets: Option<&'a [i64]>,
}

/// Where a chunk of a batch run writes.
struct Out<'a> {
    poses: &'a mut [f64],
    covs: &'a mut [f64],
    nis: &'a mut [f64],
    applied: &'a mut [f64],
}

/// One correction of a batch run's loop: a trait (not a closure) so that
/// the loop inlines it.
trait Correct {
    /// The reading's length (a constant for one sensor type, so that the
    /// loop indexes with no checks).
    fn dim(&self) -> usize;

    fn correct(
        &self,
        ekf: &Ekf<f64>,
        belief: &Belief<f64, 3>,
        z: &[f64],
        at: i64,
    ) -> Result<Corrected, String>;
}

/// Paper 001's IR pair, its correction inlined.
struct Ir<'a>(&'a IrPairGeometry<f64>, f64, &'a [f64; 2]);

impl Correct for Ir<'_> {
    #[inline(always)]
    fn dim(&self) -> usize {
        2
    }

    #[inline(always)]
    fn correct(
        &self,
        ekf: &Ekf<f64>,
        belief: &Belief<f64, 3>,
        z: &[f64],
        at: i64,
    ) -> Result<Corrected, String> {
        ir_correct(ekf, belief, (self.0, self.1, self.2), z, at)
    }
}

impl Correct for Sensor {
    #[inline(always)]
    fn dim(&self) -> usize {
        Self::dim(self)
    }

    #[inline(always)]
    fn correct(
        &self,
        ekf: &Ekf<f64>,
        belief: &Belief<f64, 3>,
        z: &[f64],
        at: i64,
    ) -> Result<Corrected, String> {
        Self::correct(self, ekf, belief, z, at)
    }
}

impl Steps<'_> {
    /// Steps `range` from `belief`, each written to `out` (indexed from
    /// the range's start); the last belief, or the failing step's error.
    /// The loop is made once per pair of models ([`Row`], [`Correct`]),
    /// so that each step runs as the Rust peer benchmark's does, with no
    /// dispatch.
    fn run(
        &self,
        range: core::ops::Range<usize>,
        belief: Belief<f64, 3>,
        out: Out<'_>,
    ) -> Result<Belief<f64, 3>, String> {
        match self.motion {
            Motion::DiffDrive(m) => self.sensed(range, belief, out, m),
            Motion::Unicycle(m) => self.sensed(range, belief, out, m),
            Motion::SkidSteer(m) => self.sensed(range, belief, out, m),
        }
    }

    /// [`Steps::steps`] with the sensor's correction.
    fn sensed(
        &self,
        range: core::ops::Range<usize>,
        belief: Belief<f64, 3>,
        out: Out<'_>,
        predict: &impl Row,
    ) -> Result<Belief<f64, 3>, String> {
        match self.sensor {
            Some(Sensor::IrPair { pair, arena, r }) => {
                self.steps(range, belief, out, predict, &Ir(pair, *arena, r))
            }
            // No sensor, no readings (`run` checks it): never corrects.
            Some(s) => self.steps(range, belief, out, predict, s),
            None => self.steps(range, belief, out, predict, &NoSensor),
        }
    }

    /// The loop of a batch run over `range`. Inputs, readings and results
    /// are walked by iterators (no index arithmetic, no bounds checks in
    /// the loop), so that the belief and the output cursors stay in
    /// registers.
    #[inline(always)]
    fn steps<M: Row>(
        &self,
        range: core::ops::Range<usize>,
        mut belief: Belief<f64, 3>,
        out: Out<'_>,
        predict: &M,
        correct: &impl Correct,
    ) -> Result<Belief<f64, 3>, String> {
        let (k, m) = (M::LEN, correct.dim());
        let first = range.start;
        let inputs = self.inputs[first * k..range.end * k].chunks_exact(k);
        // Without readings, an empty slice: every step only predicts.
        let readings = self
            .readings
            .map_or(&[][..], |z| &z[first * m..range.end * m]);
        let mut readings = readings.chunks_exact(m);
        let targets = self.targets.map_or(&[][..], |t| &t[first..range.end]);
        let mut targets = targets.iter();
        let results = out
            .poses
            .chunks_exact_mut(3)
            .zip(out.covs.chunks_exact_mut(9))
            .zip(out.nis.iter_mut().zip(out.applied.iter_mut()));
        for (j, (u, ((pose, cov), (nis, applied)))) in inputs.zip(results).enumerate() {
            belief = self
                .ekf
                .predict(&belief, predict, &M::input(u))
                .map_err(|e| format!("step {}: predict: {e}", first + j))?;
            let z = readings.next();
            let at = targets.next().copied().unwrap_or(0);
            *nis = f64::NAN;
            *applied = 0.0;
            if let Some(z) = z
                && !z.iter().all(|v| v.is_nan())
            {
                let (b, v, a) = correct
                    .correct(self.ekf, &belief, z, at)
                    .map_err(|e| format!("step {}: {e}", first + j))?
                    .map_err(|e| format!("step {}: update: {e}", first + j))?;
                belief = b;
                *nis = v;
                *applied = if a { 1.0 } else { 0.0 };
            }
            pose.copy_from_slice(belief.x.as_slice());
            cov.copy_from_slice(belief.p.as_slice());
        }
        Ok(belief)
    }
}

/// A filter without a sensor: a batch run without readings.
struct NoSensor;

impl Correct for NoSensor {
    fn dim(&self) -> usize {
        1
    }

    fn correct(
        &self,
        _ekf: &Ekf<f64>,
        _belief: &Belief<f64, 3>,
        _z: &[f64],
        _at: i64,
    ) -> Result<Corrected, String> {
        Err("this filter has no sensor".to_string())
    }
}

/// The motion's input as three numbers (the third unused by a
/// two-number input).
pub fn input3(motion: &Motion, u: &Bound<'_, PyAny>) -> PyResult<[f64; 3]> {
    if motion.input_len() == 2 {
        let [a, b] = arrays::fixed::<2>("u", u)?;
        Ok([a, b, 0.0])
    } else {
        arrays::fixed::<3>("u", u)
    }
}
