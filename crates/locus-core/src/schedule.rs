//! The 11-step correction schedule of papers 000 and 003.
//!
//! The FPGA correction core of seed 003 (states waiting, mult1, mult2,
//! multadd, add, div1) executes the EKF correction as eleven operations with
//! named intermediates (spec section 1, table "The 11-step correction
//! schedule"). This module executes the same steps, in the same order, and
//! returns every intermediate, so the schedule can be checked against the
//! generic correction and used as the reference of a cycle-level hardware
//! model.
//!
//! The schedule is the papers' **plain** covariance update
//! (`P+ = P- - G H P-`), not Joseph.

use nalgebra::{SMatrix, SVector};

use crate::belief::all_finite;
use crate::{Belief, Error, Input, MeasurementModel, Scalar};

/// Every intermediate of one scheduled correction (`N` states, `M`
/// measurement components; the paper's core has N = 3, M = 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Steps<T: Scalar, const N: usize, const M: usize> {
    /// Step 1: `O1 = P- H^T` (N x M).
    pub o1: SMatrix<T, N, M>,
    /// Step 2: `O2 = H O1` (M x M).
    pub o2: SMatrix<T, M, M>,
    /// Step 3: `O3 = O2 + R` (M x M), the innovation covariance `S`.
    pub o3: SMatrix<T, M, M>,
    /// Step 4: `O4 = inv(O3)` (M x M).
    pub o4: SMatrix<T, M, M>,
    /// Step 5: `G = O1 O4` (N x M), the gain.
    pub g: SMatrix<T, N, M>,
    /// Step 6: `O5 = z - h(X-)` (M), the innovation (angles wrapped by the model).
    pub o5: SVector<T, M>,
    /// Step 7: `O6 = G O5` (N).
    pub o6: SVector<T, N>,
    /// Step 8: `X+ = X- + O6` (N).
    pub x_post: SVector<T, N>,
    /// Step 9: `O7 = G H` (N x N).
    pub o7: SMatrix<T, N, N>,
    /// Step 10: `O8 = O7 P-` (N x N).
    pub o8: SMatrix<T, N, N>,
    /// Step 11: `P+ = P- - O8` (N x N).
    pub p_post: SMatrix<T, N, N>,
}

impl<T: Scalar, const N: usize, const M: usize> Steps<T, N, M> {
    /// The posterior belief `(X+, P+)`.
    pub fn belief(&self) -> Belief<T, N> {
        Belief {
            x: self.x_post,
            p: self.p_post,
        }
    }
}

/// Runs the 11-step schedule on a prior belief and one measurement.
///
/// `H`, `h(X-)` and `R` (the model's `V R V^T`) are computed "in software" from
/// the model, as the papers' Nios II did, and fed to the schedule.
///
/// Errors: non-finite inputs, no measurement at this state, or `O3` singular
/// (step 4 cannot invert it).
pub fn correct_11_step<T, Me, const N: usize, const M: usize>(
    belief: &Belief<T, N>,
    model: &Me,
    z: &SVector<T, M>,
) -> Result<Steps<T, N, M>, Error>
where
    T: Scalar,
    Me: MeasurementModel<T, N, M>,
{
    belief.validate()?;
    if !all_finite(z.as_slice()) {
        return Err(Error::NonFinite(Input::Measurement));
    }
    let z_hat = model.h(&belief.x).ok_or(Error::NoMeasurement)?;
    let h = model.jacobian(&belief.x);
    let r = model.noise(&belief.x);
    if !(all_finite(z_hat.as_slice()) && all_finite(h.as_slice())) {
        return Err(Error::NonFinite(Input::MeasurementModel));
    }
    if !all_finite(r.as_slice()) {
        return Err(Error::NonFinite(Input::MeasurementNoise));
    }
    let p = belief.p;
    let o1 = p * h.transpose(); // 1
    let o2 = h * o1; // 2
    let o3 = o2 + r; // 3
    let o4 = o3
        .try_inverse()
        .ok_or(Error::InnovationNotPositiveDefinite)?; // 4
    let g = o1 * o4; // 5
    let o5 = model.residual(z, &z_hat); // 6
    let o6 = g * o5; // 7
    let x_post = belief.x + o6; // 8
    let o7 = g * h; // 9
    let o8 = o7 * p; // 10
    let p_post = p - o8; // 11
    if !(all_finite(x_post.as_slice()) && all_finite(p_post.as_slice())) {
        return Err(Error::InnovationNotPositiveDefinite);
    }
    Ok(Steps {
        o1,
        o2,
        o3,
        o4,
        g,
        o5,
        o6,
        x_post,
        o7,
        o8,
        p_post,
    })
}
