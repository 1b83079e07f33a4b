//! The Extended Kalman Filter: predict, correct (batch and sequential), gating.
//!
//! [`Ekf`] is configuration only (covariance-update form, optional gate); it
//! holds no estimate. Every operation takes a [`Belief`] by reference and
//! returns a new one, so **on any error the caller's belief is unchanged**.
//!
//! Equations (spec section 1, all seeds):
//!
//! * predict: `X- = f(X+, u, 0)`, `P- = A P+ A^T + W Q W^T`;
//! * correct: `S = H P- H^T + V R V^T`, `G = P- H^T S^-1`,
//!   `X+ = X- + G (z - h(X-))`, and `P+` by the chosen [`CovarianceUpdate`].
//!
//! Neither operation allocates.

use nalgebra::{SMatrix, SVector};

use crate::belief::{all_finite, all_finite_pair, finite};
use crate::linalg::{joseph, mul, mul_bt, sandwich, spd_inverse};
use crate::{Belief, ChiSquareGate, Error, Input, MeasurementModel, MotionModel, Scalar};

/// How the corrected covariance `P+` is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CovarianceUpdate {
    /// Joseph form `(I - G H) P (I - G H)^T + G (V R V^T) G^T`: positive
    /// semi-definite by construction and valid for any gain; each product is
    /// computed on its upper triangle and mirrored, so the result is exactly
    /// symmetric. The default.
    #[default]
    Joseph,
    /// The papers' plain form `P+ = P- - G H P-` (cheapest; can lose symmetry
    /// and definiteness to rounding).
    Plain,
    /// The plain form followed by `(P + P^T) / 2`.
    ForcedSymmetric,
}

/// Which components of a measurement are present: `mask[i] == false` marks
/// component `i` as missing. A missing component is excluded exactly (as if
/// the measurement had only the present components); its value in `z` is not
/// read, so it may hold anything. Never mark a missing value by NaN: a NaN in a
/// present component is an error.
pub type Mask<const M: usize> = [bool; M];

/// The result of a correction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correction<T: Scalar, const N: usize, const M: usize> {
    /// The posterior if the update was applied, the prior (unchanged) if the
    /// gate rejected it.
    pub belief: Belief<T, N>,
    /// The innovation `z - h(X-)` (angles wrapped; zero in missing components).
    pub innovation: SVector<T, M>,
    /// The normalised innovation squared `nu^T S^-1 nu` (dimensionless).
    pub nis: T,
    /// Degrees of freedom of the NIS: the number of present components.
    pub dof: u32,
    /// Whether the update was applied (`false`: rejected by the gate).
    pub applied: bool,
    /// The innovation covariance `S = H P- H^T + V R V^T` at the prior
    /// (missing components: zero row and column, unit diagonal).
    pub s: SMatrix<T, M, M>,
    /// The gain `G = P- H^T S^-1` (zero columns for missing components).
    /// Computed whether or not the gate applied the update, so a rejected
    /// correction still shows what it would have done.
    pub gain: SMatrix<T, N, M>,
}

/// The filter's configuration. Holds no estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ekf<T: Scalar> {
    /// The covariance update of the correction (Joseph by default).
    pub update: CovarianceUpdate,
    /// An optional chi-square gate on the NIS: a correction whose NIS exceeds
    /// the gate's threshold for its degrees of freedom is not applied.
    pub gate: Option<ChiSquareGate<T>>,
}

impl<T: Scalar> Default for Ekf<T> {
    fn default() -> Self {
        Self {
            update: CovarianceUpdate::Joseph,
            gate: None,
        }
    }
}

/// The linearisation of a measurement at the prior, with missing components
/// neutralised: row of `H` zero, residual zero, noise row/column zero with a
/// unit diagonal. This makes the batch and the sequential update ignore them
/// exactly.
struct Linearised<T: Scalar, const N: usize, const M: usize> {
    nu: SVector<T, M>,
    h: SMatrix<T, M, N>,
    r: SMatrix<T, M, M>,
    dof: u32,
}

impl<T: Scalar> Ekf<T> {
    /// A filter with the given covariance update and no gate.
    pub fn new(update: CovarianceUpdate) -> Self {
        Self { update, gate: None }
    }

    /// The same filter with a chi-square gate.
    pub fn with_gate(mut self, gate: ChiSquareGate<T>) -> Self {
        self.gate = Some(gate);
        self
    }

    /// Prediction step: `X- = f(X+, u, 0)`, `P- = A P+ A^T + W Q W^T`
    /// (kept exactly symmetric; `P+` must be symmetric).
    ///
    /// Errors: non-finite belief, input, noise or model output. On error the
    /// caller's belief is untouched (it is only borrowed).
    ///
    /// Checking: the prior and the input (the model's own check) before any
    /// arithmetic, then the outputs (finite inputs can still overflow); if
    /// anything is not finite, a cold path finds and names the offending
    /// input.
    #[inline(always)]
    pub fn predict<Mo, const N: usize, const NQ: usize>(
        &self,
        belief: &Belief<T, N>,
        model: &Mo,
        u: &Mo::Input,
    ) -> Result<Belief<T, N>, Error>
    where
        Mo: MotionModel<T, N, NQ>,
    {
        // The prior is checked first: a model's `propagate` may read only one
        // triangle of the symmetric `P`, so a NaN in the other need not reach
        // the output.
        if model.input_is_finite(u) && all_finite_pair(belief.x.as_slice(), belief.p.as_slice()) {
            let (x, p) = model.propagate(&belief.x, u, &belief.p);
            if all_finite_pair(x.as_slice(), p.as_slice()) {
                return Ok(Belief { x, p });
            }
        }
        Err(diagnose_predict(belief, model, u))
    }

    /// Batch correction with every component present.
    #[inline]
    pub fn correct<Me, const N: usize, const M: usize>(
        &self,
        belief: &Belief<T, N>,
        model: &Me,
        z: &SVector<T, M>,
    ) -> Result<Correction<T, N, M>, Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        self.correct_masked(belief, model, z, &[true; M])
    }

    /// Batch correction: `S = H P H^T + V R V^T`, `G = P H^T S^-1`,
    /// `X+ = X- + G nu`, `P+` by [`Ekf::update`]. Components with
    /// `mask[i] == false` are excluded exactly.
    ///
    /// Errors: non-finite belief, measurement or model output; no measurement
    /// predicted at this state; `S` not positive definite; every component
    /// missing. A gated-out measurement is not an error: the result has
    /// `applied == false` and the prior belief.
    ///
    /// Checking, on the fast path: the prior (`X-`, `P-`) before any
    /// arithmetic (off the critical path), then the NIS, which is not finite
    /// if the innovation, the measurement, `h` or any entry of `S^-1` is
    /// not (every entry of `S^-1` multiplies into it, and `0 * inf` is NaN).
    /// `S` itself must be numerically positive definite (a determinant or
    /// pivot above machine epsilon relative to the diagonal), which bounds
    /// `S^-1` and so the gain. With those, the posterior is finite unless a
    /// product of finite values overflows: in exact arithmetic
    /// `|(G H P)_ij| <= sqrt(P_ii P_jj)` and `|(G nu)_i| <= sqrt(P_ii NIS)`,
    /// so that needs covariances near the largest float (about 1e308 in f64,
    /// 3e38 in f32). The posterior and the gain themselves are not checked:
    /// that branch would wait for the last product.
    #[inline(always)]
    pub fn correct_masked<Me, const N: usize, const M: usize>(
        &self,
        belief: &Belief<T, N>,
        model: &Me,
        z: &SVector<T, M>,
        mask: &Mask<M>,
    ) -> Result<Correction<T, N, M>, Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        let dof = present(mask)?;
        let inputs_finite = all_finite_pair(belief.x.as_slice(), belief.p.as_slice());
        let Some(lin) = linearise_unchecked(belief, model, z, mask, dof) else {
            return Err(diagnose_correct(belief, model, z, mask).unwrap_or(Error::NoMeasurement));
        };
        let p = &belief.p;
        let (mut pht, mut hph) = model.project(&belief.x, &lin.h, p);
        for (i, present) in mask.iter().enumerate() {
            if !present {
                pht.column_mut(i).fill(T::zero());
                hph.row_mut(i).fill(T::zero());
                hph.column_mut(i).fill(T::zero());
            }
        }
        let s = hph + lin.r;
        let Some(s_inv) = spd_inverse(&s) else {
            return Err(diagnose_correct(belief, model, z, mask)
                .unwrap_or(Error::InnovationNotPositiveDefinite));
        };
        // y = S^-1 nu serves both the NIS (nu . y) and the state update
        // (G nu = P H^T y), so the state does not wait for the gain.
        // These three small products use nalgebra's operators, which LLVM
        // inlines here: they execute fewer instructions than the `linalg`
        // kernels, with bit-identical results.
        let y = s_inv * lin.nu;
        let nis = lin.nu.dot(&y);
        if !finite(nis) {
            return Err(diagnose_correct(belief, model, z, mask)
                .unwrap_or(Error::InnovationNotPositiveDefinite));
        }
        if let Some(gate) = &self.gate {
            if !gate.accepts(nis, dof as usize) {
                if let Some(err) = diagnose_correct(belief, model, z, mask) {
                    return Err(err);
                }
                return Ok(Correction {
                    belief: *belief,
                    innovation: lin.nu,
                    nis,
                    dof,
                    applied: false,
                    s,
                    gain: pht * s_inv,
                });
            }
        }
        let x = belief.x + pht * y;
        let g = pht * s_inv;
        let p_post = match self.update {
            CovarianceUpdate::Joseph => joseph(p, &pht, &lin.h, &g, &lin.r),
            CovarianceUpdate::Plain => p - mul_bt(&g, &pht),
            CovarianceUpdate::ForcedSymmetric => symmetrise(p - mul_bt(&g, &pht)),
        };
        if inputs_finite {
            return Ok(Correction {
                belief: Belief { x, p: p_post },
                innovation: lin.nu,
                nis,
                dof,
                applied: true,
                s,
                gain: g,
            });
        }
        Err(diagnose_correct(belief, model, z, mask).unwrap_or(Error::NonFinite(Input::Covariance)))
    }

    /// Sequential scalar correction with every component present.
    #[inline]
    pub fn correct_sequential<Me, const N: usize, const M: usize>(
        &self,
        belief: &Belief<T, N>,
        model: &Me,
        z: &SVector<T, M>,
    ) -> Result<Correction<T, N, M>, Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        self.correct_sequential_masked(belief, model, z, &[true; M])
    }

    /// Sequential scalar correction (spec section 1, "Sequential correction").
    ///
    /// `h` and `H` are evaluated once, at the prior. If the effective noise
    /// `V R V^T` is not diagonal it is first decorrelated by its Cholesky
    /// factor `L` (`nu' = L^-1 nu`, `H' = L^-1 H`, unit noise). The components
    /// are then applied one at a time, each with one division and no matrix
    /// inverse; component `i` sees the innovation `nu'_i - H'_i (x - x_prior)`
    /// so that the result equals the batch update in exact arithmetic. The NIS
    /// is the sum of the scalar normalised innovations, which equals the batch
    /// `nu^T S^-1 nu`; the gate (if any) is applied to it, and a rejected
    /// update returns the prior.
    #[inline]
    pub fn correct_sequential_masked<Me, const N: usize, const M: usize>(
        &self,
        belief: &Belief<T, N>,
        model: &Me,
        z: &SVector<T, M>,
        mask: &Mask<M>,
    ) -> Result<Correction<T, N, M>, Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        let dof = present(mask)?;
        if let Some(err) = diagnose_correct(belief, model, z, mask) {
            return Err(err);
        }
        let lin = linearise_unchecked(belief, model, z, mask, dof).ok_or(Error::NoMeasurement)?;
        let (nu_d, h_d, r_d) = if is_diagonal(&lin.r) {
            (lin.nu, lin.h, lin.r.diagonal())
        } else {
            let chol = lin.r.cholesky().ok_or(Error::NoiseNotPositiveDefinite)?;
            let l = chol.l();
            let nu_d = l
                .solve_lower_triangular(&lin.nu)
                .ok_or(Error::NoiseNotPositiveDefinite)?;
            let h_d = l
                .solve_lower_triangular(&lin.h)
                .ok_or(Error::NoiseNotPositiveDefinite)?;
            (nu_d, h_d, SVector::<T, M>::repeat(T::one()))
        };
        // S and the gain at the prior, for the caller (the scalar updates
        // below never form them).
        let s = mul_bt(&mul(&lin.h, &belief.p), &lin.h) + lin.r;
        let gain = spd_inverse(&s)
            .map(|s_inv| mul_bt(&belief.p, &lin.h) * s_inv)
            .ok_or(Error::InnovationNotPositiveDefinite)?;
        let x0 = belief.x;
        let mut x = belief.x;
        let mut p = belief.p;
        let mut nis = T::zero();
        for i in 0..M {
            if !mask[i] {
                continue;
            }
            let hi = h_d.row(i);
            let innovation = nu_d[i] - (hi * (x - x0))[0];
            let a = p * hi.transpose(); // P h^T, N x 1
            let s = (hi * a)[0] + r_d[i];
            if !(s > T::zero() && finite(s)) {
                return Err(Error::InnovationNotPositiveDefinite);
            }
            let k = a / s;
            x += k * innovation;
            nis += innovation * innovation / s;
            p = match self.update {
                CovarianceUpdate::Joseph => {
                    let ikh = SMatrix::<T, N, N>::identity() - k * hi;
                    sandwich(&ikh, &p) + mul_bt(&k, &k) * r_d[i]
                }
                CovarianceUpdate::Plain => p - k * a.transpose(),
                CovarianceUpdate::ForcedSymmetric => symmetrise(p - k * a.transpose()),
            };
        }
        if let Some(gate) = &self.gate {
            if !gate.accepts(nis, lin.dof as usize) {
                return Ok(Correction {
                    belief: *belief,
                    innovation: lin.nu,
                    nis,
                    dof: lin.dof,
                    applied: false,
                    s,
                    gain,
                });
            }
        }
        finish(x, p, lin.nu, nis, lin.dof, s, gain)
    }
}

/// The number of present components, or an error if there is none.
#[inline(always)]
fn present<const M: usize>(mask: &Mask<M>) -> Result<u32, Error> {
    let dof = mask.iter().filter(|present| **present).count() as u32;
    if dof == 0 {
        Err(Error::NothingToCorrect)
    } else {
        Ok(dof)
    }
}

/// Evaluates `h`, `H`, `V R V^T` and the residual at the prior (unchecked),
/// and neutralises missing components. `None` if the model has no
/// measurement at this state.
#[inline(always)]
fn linearise_unchecked<T, Me, const N: usize, const M: usize>(
    belief: &Belief<T, N>,
    model: &Me,
    z: &SVector<T, M>,
    mask: &Mask<M>,
    dof: u32,
) -> Option<Linearised<T, N, M>>
where
    T: Scalar,
    Me: MeasurementModel<T, N, M>,
{
    let (z_hat, mut h) = model.linearize(&belief.x)?;
    let mut r = model.noise(&belief.x);
    // Missing components of z may hold anything (even NaN): replace them by the
    // prediction before forming the residual, then neutralise them.
    let mut z_used = *z;
    for i in 0..M {
        if !mask[i] {
            z_used[i] = z_hat[i];
        }
    }
    let mut nu = model.residual(&z_used, &z_hat);
    for i in 0..M {
        if !mask[i] {
            nu[i] = T::zero();
            h.row_mut(i).fill(T::zero());
            r.row_mut(i).fill(T::zero());
            r.column_mut(i).fill(T::zero());
            r[(i, i)] = T::one();
        }
    }
    Some(Linearised { nu, h, r, dof })
}

/// The cold path of `predict`: names the first non-finite input.
#[cold]
#[inline(never)]
fn diagnose_predict<T, Mo, const N: usize, const NQ: usize>(
    belief: &Belief<T, N>,
    model: &Mo,
    u: &Mo::Input,
) -> Error
where
    T: Scalar,
    Mo: MotionModel<T, N, NQ>,
{
    if let Err(err) = belief.validate() {
        return err;
    }
    if !model.input_is_finite(u) {
        return Error::NonFinite(Input::Control);
    }
    if !all_finite(model.noise_cov(u).as_slice()) {
        return Error::NonFinite(Input::ProcessNoise);
    }
    let (x, a, w) = model.linearize(&belief.x, u);
    if !(all_finite(x.as_slice()) && all_finite(a.as_slice()) && all_finite(w.as_slice())) {
        return Error::NonFinite(Input::MotionModel);
    }
    // Finite inputs, non-finite result: the covariance overflowed.
    Error::NonFinite(Input::Covariance)
}

/// The cold path of the corrections: the first non-finite input, or `None`
/// if every input is finite (the caller then names the numerical failure).
#[cold]
#[inline(never)]
fn diagnose_correct<T, Me, const N: usize, const M: usize>(
    belief: &Belief<T, N>,
    model: &Me,
    z: &SVector<T, M>,
    mask: &Mask<M>,
) -> Option<Error>
where
    T: Scalar,
    Me: MeasurementModel<T, N, M>,
{
    if let Err(err) = belief.validate() {
        return Some(err);
    }
    if (0..M).any(|i| mask[i] && !z[i].is_finite()) {
        return Some(Error::NonFinite(Input::Measurement));
    }
    let z_hat = model.h(&belief.x)?;
    if !(all_finite(z_hat.as_slice()) && all_finite(model.jacobian(&belief.x).as_slice())) {
        return Some(Error::NonFinite(Input::MeasurementModel));
    }
    if !all_finite(model.noise(&belief.x).as_slice()) {
        return Some(Error::NonFinite(Input::MeasurementNoise));
    }
    let mut z_used = *z;
    for i in 0..M {
        if !mask[i] {
            z_used[i] = z_hat[i];
        }
    }
    if !all_finite(model.residual(&z_used, &z_hat).as_slice()) {
        return Some(Error::NonFinite(Input::MeasurementModel));
    }
    None
}

#[inline(always)]
fn finish<T: Scalar, const N: usize, const M: usize>(
    x: SVector<T, N>,
    p: SMatrix<T, N, N>,
    innovation: SVector<T, M>,
    nis: T,
    dof: u32,
    s: SMatrix<T, M, M>,
    gain: SMatrix<T, N, M>,
) -> Result<Correction<T, N, M>, Error> {
    if !all_finite(x.as_slice()) {
        return Err(Error::NonFinite(Input::State));
    }
    if !all_finite(p.as_slice()) {
        return Err(Error::NonFinite(Input::Covariance));
    }
    Ok(Correction {
        belief: Belief { x, p },
        innovation,
        nis,
        dof,
        applied: true,
        s,
        gain,
    })
}

/// `(P + P^T) / 2`.
#[inline]
pub fn symmetrise<T: Scalar, const N: usize>(p: SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    let half = crate::cast::<T>(0.5);
    (p + p.transpose()) * half
}

fn is_diagonal<T: Scalar, const M: usize>(r: &SMatrix<T, M, M>) -> bool {
    (0..M).all(|i| (0..M).all(|j| i == j || r[(i, j)] == T::zero()))
}
