//! Small fixed-size matrix kernels for the filter's hot path.
//!
//! Written as plain loops over const dimensions and marked
//! `#[inline(always)]`, so that each instance is unrolled into its caller.
//! nalgebra's operators compute the same, but inside the large generic
//! `predict`/`correct` LLVM tends to leave them as out-of-line calls with
//! matrices passed through memory (measured: ~40 ns of a ~250 ns 3-state step).

use nalgebra::SMatrix;

use crate::Scalar;
use crate::belief::finite;

/// `A B`.
///
/// Column-oriented (`out[:, j] += A[:, k] B[k, j]`, `k` ascending): each
/// term is the same scalar sum as the dot-product form, in the same order,
/// but the innermost loop runs down a contiguous column, which LLVM packs
/// into SIMD multiply-adds the way nalgebra's own small-matrix product does.
#[inline(always)]
pub(crate) fn mul<T: Scalar, const R: usize, const K: usize, const C: usize>(
    a: &SMatrix<T, R, K>,
    b: &SMatrix<T, K, C>,
) -> SMatrix<T, R, C> {
    let mut out = SMatrix::<T, R, C>::zeros();
    for j in 0..C {
        for i in 0..R {
            let mut acc = T::zero();
            for k in 0..K {
                acc += a[(i, k)] * b[(k, j)];
            }
            out[(i, j)] = acc;
        }
    }
    out
}

/// `A B^T` (column-oriented like [`mul`]).
#[inline(always)]
pub(crate) fn mul_bt<T: Scalar, const R: usize, const K: usize, const C: usize>(
    a: &SMatrix<T, R, K>,
    b: &SMatrix<T, C, K>,
) -> SMatrix<T, R, C> {
    let mut out = SMatrix::<T, R, C>::zeros();
    for j in 0..C {
        for i in 0..R {
            let mut acc = T::zero();
            for k in 0..K {
                acc += a[(i, k)] * b[(j, k)];
            }
            out[(i, j)] = acc;
        }
    }
    out
}

/// `A M A^T` for a symmetric `M`: the full product (vectorised as in
/// [`mul`]), then the upper triangle mirrored onto the lower, so the result is
/// exactly symmetric.
#[inline(always)]
pub(crate) fn sandwich<T: Scalar, const R: usize, const K: usize>(
    a: &SMatrix<T, R, K>,
    m: &SMatrix<T, K, K>,
) -> SMatrix<T, R, R> {
    let mut out = mul_bt(&mul(a, m), a);
    for j in 0..R {
        for i in (j + 1)..R {
            out[(i, j)] = out[(j, i)];
        }
    }
    out
}

/// The Joseph form `(I - G H) P (I - G H)^T + G R G^T` of a correction
/// of gain `G` (`N x M`), given `P H^T` (`pht`): `A = (I - G H) P = P - G
/// (P H^T)^T` (`P` symmetric), then `A (I - G H)^T = A - (A H^T) G^T`, then
/// `+ G R G^T`, the upper triangle mirrored onto the lower. The same
/// product grouped as rank-`M` updates: `3 N^2 M` multiplications where
/// the `N x N` products take `2 N^3` (8 states, one reading: 192 against
/// 1024), and still the sum of `(I - G H) P (I - G H)^T` and `G R G^T`
/// whatever the gain's rounding, which is what the Joseph form is for.
#[inline(always)]
pub(crate) fn joseph<T: Scalar, const N: usize, const M: usize>(
    p: &SMatrix<T, N, N>,
    pht: &SMatrix<T, N, M>,
    h: &SMatrix<T, M, N>,
    g: &SMatrix<T, N, M>,
    r: &SMatrix<T, M, M>,
) -> SMatrix<T, N, N> {
    let a = p - mul_bt(g, pht);
    let aht = mul_bt(&a, h);
    let grg = mul(g, r);
    let mut out = SMatrix::<T, N, N>::zeros();
    for j in 0..N {
        for i in 0..=j {
            let mut acc = a[(i, j)];
            for k in 0..M {
                acc += grg[(i, k)] * g[(j, k)] - aht[(i, k)] * g[(j, k)];
            }
            out[(i, j)] = acc;
            out[(j, i)] = acc;
        }
    }
    out
}

/// The inverse of a symmetric positive-definite matrix, or `None` if it is
/// not positive definite, numerically singular (a pivot or determinant below
/// machine epsilon relative to its diagonal) or not finite. Closed form for 1x1 and 2x2
/// (positive-definiteness by `s00 > 0` and `det > 0`); an LDL^T
/// factorisation (no square roots) above.
#[inline(always)]
pub(crate) fn spd_inverse<T: Scalar, const M: usize>(
    s: &SMatrix<T, M, M>,
) -> Option<SMatrix<T, M, M>> {
    let zero = T::zero();
    match M {
        1 => {
            let d = s[(0, 0)];
            // `>` is false for NaN.
            (d > zero && finite(d)).then(|| SMatrix::from_element(T::one() / d))
        }
        2 => {
            let (a, b, c, d) = (s[(0, 0)], s[(0, 1)], s[(1, 0)], s[(1, 1)]);
            let det = a * d - b * c;
            // Numerically singular (condition number beyond 1/eps) counts as
            // not positive definite: its inverse would be rounding noise, and
            // bounding it keeps the gain finite for finite inputs.
            if !(a > zero && det > a * d * T::default_epsilon() && finite(det)) {
                return None;
            }
            let inv_det = T::one() / det;
            let mut out = SMatrix::<T, M, M>::zeros();
            out[(0, 0)] = d * inv_det;
            out[(0, 1)] = -b * inv_det;
            out[(1, 0)] = -c * inv_det;
            out[(1, 1)] = a * inv_det;
            Some(out)
        }
        _ => ldlt_inverse(s),
    }
}

/// Inverse through `S = L D L^T` (unit lower `L`), `None` unless every pivot
/// of `D` is positive and finite.
fn ldlt_inverse<T: Scalar, const M: usize>(s: &SMatrix<T, M, M>) -> Option<SMatrix<T, M, M>> {
    let zero = T::zero();
    let mut l = SMatrix::<T, M, M>::identity();
    let mut d = [zero; M];
    for j in 0..M {
        let mut dj = s[(j, j)];
        for k in 0..j {
            dj -= l[(j, k)] * l[(j, k)] * d[k];
        }
        // A pivot below eps times its diagonal entry: numerically singular.
        if !(dj > zero && dj > s[(j, j)] * T::default_epsilon() && finite(dj)) {
            return None;
        }
        d[j] = dj;
        for i in (j + 1)..M {
            let mut v = s[(i, j)];
            for k in 0..j {
                v -= l[(i, k)] * l[(j, k)] * d[k];
            }
            l[(i, j)] = v / dj;
        }
    }
    // Solve L D L^T X = I column by column.
    let mut inv = SMatrix::<T, M, M>::zeros();
    for c in 0..M {
        let mut y = [zero; M];
        for i in 0..M {
            let mut v = if i == c { T::one() } else { zero };
            for k in 0..i {
                v -= l[(i, k)] * y[k];
            }
            y[i] = v;
        }
        for (yi, di) in y.iter_mut().zip(d.iter()) {
            *yi /= *di;
        }
        for i in (0..M).rev() {
            let mut v = y[i];
            for k in (i + 1)..M {
                v -= l[(k, i)] * inv[(k, c)];
            }
            inv[(i, c)] = v;
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Matrix3, Matrix4};

    #[test]
    fn spd_inverse_matches_nalgebra_and_rejects_indefinite() {
        let s2 = Matrix2::new(4.0, 1.0, 1.0, 3.0);
        let i2 = spd_inverse(&s2).unwrap();
        assert!((i2 - s2.try_inverse().unwrap()).amax() < 1e-15);
        let s4 = Matrix4::new(
            4.0, 1.0, 0.5, 0.1, 1.0, 3.0, 0.2, 0.3, 0.5, 0.2, 2.0, 0.4, 0.1, 0.3, 0.4, 1.5,
        );
        let i4 = spd_inverse(&s4).unwrap();
        assert!((i4 * s4 - Matrix4::identity()).amax() < 1e-14);
        assert!(spd_inverse(&Matrix2::new(1.0, 2.0, 2.0, 1.0)).is_none());
        assert!(spd_inverse(&Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0)).is_none());
        assert!(spd_inverse(&Matrix2::new(f64::NAN, 0.0, 0.0, 1.0)).is_none());
        assert!(spd_inverse(&nalgebra::Matrix1::new(0.0)).is_none());
    }

    #[test]
    fn kernels_match_nalgebra() {
        let a = Matrix3::new(1.0, 2.0, 3.0, -1.0, 0.5, 2.0, 0.0, 1.0, -2.0);
        let p = Matrix3::new(2.0, 0.3, 0.1, 0.3, 1.0, 0.2, 0.1, 0.2, 0.5);
        assert_eq!(mul(&a, &p), a * p);
        assert_eq!(mul_bt(&a, &p), a * p.transpose());
        assert!((sandwich(&a, &p) - a * p * a.transpose()).amax() < 1e-14);
    }

    /// The grouped Joseph form equals the product written out, for any
    /// gain (the optimal one and one off by a tenth), with one reading
    /// and two, and is exactly symmetric.
    #[test]
    fn joseph_is_the_product_written_out() {
        use nalgebra::{SMatrix, SVector};
        let p = SMatrix::<f64, 4, 4>::from_fn(|i, j| {
            let v = SVector::<f64, 4>::from([1.0, 0.5, -0.3, 0.2]);
            0.1 * v[i] * v[j] + if i == j { 1.0 + i as f64 } else { 0.0 }
        });
        let h2 = SMatrix::<f64, 2, 4>::new(1.0, 0.0, 0.5, 0.0, 0.0, -1.0, 0.2, 0.3);
        let r2 = Matrix2::new(0.04, 0.01, 0.01, 0.09);
        let pht = p * h2.transpose();
        let optimal = pht * (h2 * pht + r2).try_inverse().unwrap();
        for g in [optimal, optimal * 1.1] {
            let ikh = SMatrix::<f64, 4, 4>::identity() - g * h2;
            let written = ikh * p * ikh.transpose() + g * r2 * g.transpose();
            let grouped = joseph(&p, &pht, &h2, &g, &r2);
            assert!((grouped - written).amax() < 1e-14, "{grouped} {written}");
            assert_eq!(grouped, grouped.transpose());
        }
        let h1 = h2.fixed_rows::<1>(1).into_owned();
        let r1 = nalgebra::Matrix1::new(0.09);
        let pht = p * h1.transpose();
        let g = pht / (h1 * pht + r1)[(0, 0)];
        let ikh = SMatrix::<f64, 4, 4>::identity() - g * h1;
        let written = ikh * p * ikh.transpose() + g * r1 * g.transpose();
        assert!((joseph(&p, &pht, &h1, &g, &r1) - written).amax() < 1e-14);
    }
}
