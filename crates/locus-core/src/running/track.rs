//! A belief at a time ([`Track`]) and its two operations: prediction to a
//! later time, and correction by one measurement (plain or Student-t
//! weighted, with the gate's recovery as the [`Rules`] say), returning
//! what it did ([`Update`]). On any error the track is unchanged. Times
//! in s.

use nalgebra::SVector;

use super::Rules;
use crate::{
    Belief, Correction, Ekf, Error, MeasurementModel, MotionModel, Scalar, ScaledNoise, StudentT,
};

/// What a correction did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Update<T: Scalar, const N: usize, const M: usize> {
    /// The measurement corrected the belief. `first` is the attempt on the
    /// belief before an inflation, if the covariance was inflated first
    /// (the measurement was then applied only after recovery).
    Applied {
        /// The applied correction: posterior, `S` and gain as applied (with
        /// the noise divided by `weight`); its NIS is the one the gate
        /// tested, against the nominal noise.
        correction: Correction<T, N, M>,
        /// The rejected attempt before the inflation, if any.
        first: Option<Correction<T, N, M>>,
        /// The weight the correction was applied with, in (0, 1]: 1 without
        /// [`Track::correct_robust`].
        weight: T,
    },
    /// The gate rejected the measurement; the belief is kept (inflated if
    /// `first` is set: the retry after the inflation was rejected too).
    Gated {
        /// The (last) rejected attempt.
        correction: Correction<T, N, M>,
        /// The rejected attempt before the inflation, if any.
        first: Option<Correction<T, N, M>>,
    },
    /// The model predicts no measurement at this state (nothing changed).
    NoMeasurement,
}

impl<T: Scalar, const N: usize, const M: usize> Update<T, N, M> {
    /// Whether the measurement corrected the belief.
    pub fn applied(&self) -> bool {
        matches!(self, Update::Applied { .. })
    }

    /// Whether the covariance was inflated by the recovery.
    pub fn inflated(&self) -> bool {
        matches!(
            self,
            Update::Applied { first: Some(_), .. } | Update::Gated { first: Some(_), .. }
        )
    }

    /// The attempt on the belief as it was before this call (before any
    /// inflation): its NIS and `S` are those of the measurement against
    /// the prior. `None` for [`Update::NoMeasurement`].
    pub fn first_attempt(&self) -> Option<&Correction<T, N, M>> {
        match self {
            Update::Applied {
                correction, first, ..
            }
            | Update::Gated { correction, first } => Some(first.as_ref().unwrap_or(correction)),
            Update::NoMeasurement => None,
        }
    }

    /// The last attempt (the applied one, or the last rejected one).
    pub fn correction(&self) -> Option<&Correction<T, N, M>> {
        match self {
            Update::Applied { correction, .. } | Update::Gated { correction, .. } => {
                Some(correction)
            }
            Update::NoMeasurement => None,
        }
    }
}

/// The belief at a time and what is carried beside it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Track<T: Scalar, const N: usize, X = ()> {
    /// The belief.
    pub belief: Belief<T, N>,
    /// The time of the belief, s.
    pub time: f64,
    /// Consecutive gate rejections so far.
    pub rejections: u32,
    /// The caller's data carried with the belief (restored with it when
    /// the history is re-run), e.g. the input in force.
    pub extra: X,
}

impl<T: Scalar, const N: usize, X> Track<T, N, X> {
    /// A track at `time` (s) with `belief`, no rejections, and `extra`.
    pub fn new(belief: Belief<T, N>, time: f64, extra: X) -> Self {
        Self {
            belief,
            time,
            rejections: 0,
            extra,
        }
    }

    /// Prediction with `model` and input `u` (spec section 1:
    /// `X- = f(X+, u, 0)`, `P- = A P+ A^T + W Q W^T`). The time is not
    /// changed: the caller's model knows what interval `u` covers (see
    /// [`Track::predict_to`]).
    ///
    /// # Errors
    /// As [`Ekf::predict`]; the track is then unchanged.
    #[inline(always)]
    pub fn predict<Mo, const NQ: usize>(
        &mut self,
        ekf: &Ekf<T>,
        model: &Mo,
        u: &Mo::Input,
    ) -> Result<(), Error>
    where
        Mo: MotionModel<T, N, NQ>,
    {
        self.belief = ekf.predict(&self.belief, model, u)?;
        Ok(())
    }

    /// Prediction to `time` (s): `step(dt)` gives the model and input for
    /// the interval `dt = time - self.time`. Nothing happens unless
    /// `dt > 0` (an event at or before the track's time does not move it).
    ///
    /// # Errors
    /// As [`Ekf::predict`]; the track is then unchanged.
    #[inline]
    pub fn predict_to<Mo, const NQ: usize>(
        &mut self,
        ekf: &Ekf<T>,
        time: f64,
        step: impl FnOnce(f64) -> (Mo, Mo::Input),
    ) -> Result<(), Error>
    where
        Mo: MotionModel<T, N, NQ>,
    {
        let dt = time - self.time;
        if dt > 0.0 {
            let (model, u) = step(dt);
            self.belief = ekf.predict(&self.belief, &model, &u)?;
            self.time = time;
        }
        Ok(())
    }

    /// Correction with `model` and measurement `z`, behind the gate of
    /// `rules.ekf`, with `rules.recovery` (see [`Recovery`](super::Recovery)).
    ///
    /// # Errors
    /// As [`Ekf::correct`] (except [`Error::NoMeasurement`], which is
    /// [`Update::NoMeasurement`]); the track is then unchanged, even if the
    /// error came on the retry after an inflation.
    #[inline]
    pub fn correct<Me, const M: usize>(
        &mut self,
        rules: &Rules<T>,
        model: &Me,
        z: &SVector<T, M>,
    ) -> Result<Update<T, N, M>, Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        let mut belief = self.belief;
        let mut rejections = self.rejections;
        let mut first = None;
        loop {
            let c = match rules.ekf.correct(&belief, model, z) {
                Ok(c) => c,
                Err(Error::NoMeasurement) => return Ok(Update::NoMeasurement),
                Err(e) => return Err(e),
            };
            if c.applied {
                self.belief = c.belief;
                self.rejections = 0;
                return Ok(Update::Applied {
                    correction: c,
                    first,
                    weight: T::one(),
                });
            }
            rejections = rejections.saturating_add(1);
            match rules.recovery {
                Some(r) if rejections >= r.after && first.is_none() => {
                    r.inflate(&mut belief.p);
                    first = Some(c);
                }
                _ => {
                    self.belief = belief;
                    self.rejections = rejections;
                    return Ok(Update::Gated {
                        correction: c,
                        first,
                    });
                }
            }
        }
    }
    /// As [`Track::correct`], with a correction the gate lets through
    /// weighted as Student-t noise (see [`StudentT`]): heavy tails beside
    /// the gate. A correction applied after a
    /// [`Recovery`](super::Recovery) inflation keeps its nominal weight:
    /// the prior, not the measurement, was wrong. (A method of its own, so
    /// that a filter without it, e.g. the firmware, carries none of its
    /// code.)
    ///
    /// # Errors
    /// As [`Track::correct`]; the track is then unchanged.
    pub fn correct_robust<Me, const M: usize>(
        &mut self,
        rules: &Rules<T>,
        robust: &StudentT<T>,
        model: &Me,
        z: &SVector<T, M>,
    ) -> Result<Update<T, N, M>, Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        let (prior, rejections) = (self.belief, self.rejections);
        match self.correct(rules, model, z)? {
            Update::Applied {
                correction,
                first: None,
                ..
            } => {
                let (c, weight) = match Self::reweigh(rules, &prior, model, z, correction, *robust)
                {
                    Ok(r) => r,
                    Err(e) => {
                        self.belief = prior;
                        self.rejections = rejections;
                        return Err(e);
                    }
                };
                self.belief = c.belief;
                Ok(Update::Applied {
                    correction: c,
                    first: None,
                    weight,
                })
            }
            other => Ok(other),
        }
    }

    /// The correction `c` (applied at nominal noise to `belief`) redone
    /// with its Student-t weight, if that is below 1; with the weight. The
    /// NIS stays the nominal one.
    fn reweigh<Me, const M: usize>(
        rules: &Rules<T>,
        belief: &Belief<T, N>,
        model: &Me,
        z: &SVector<T, M>,
        c: Correction<T, N, M>,
        t: StudentT<T>,
    ) -> Result<(Correction<T, N, M>, T), Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        let weight = t.weight(c.nis, c.dof);
        if weight >= T::one() {
            return Ok((c, weight));
        }
        let scaled = ScaledNoise {
            inner: model,
            factor: T::one() / weight,
        };
        let ekf = Ekf {
            gate: None,
            ..rules.ekf
        };
        let mut w = ekf.correct(belief, &scaled, z)?;
        w.nis = c.nis;
        Ok((w, weight))
    }
}
