//! The Joseph covariance update's accuracy where it matters, a scan's many
//! scalar corrections of an 8-state belief, each taking most of the
//! uncertainty along its direction: computed in f32 against the same
//! corrections in f64, the Joseph form keeps the covariance symmetric
//! positive definite and close to f64's, where the plain form loses digits.

mod common;

use common::{log_uniform, rng};
use locus_core::nalgebra::{SMatrix, SVector};
use locus_core::{Belief, CovarianceUpdate, Ekf, MeasurementModel, Scalar};
use rand::RngExt;

/// `z = h x`, noise `r`.
struct Linear<T: Scalar> {
    h: SMatrix<T, 1, 8>,
    r: T,
}

impl<T: Scalar> MeasurementModel<T, 8, 1> for Linear<T> {
    fn evaluate(
        &self,
        x: &SVector<T, 8>,
        jacobian: Option<&mut SMatrix<T, 1, 8>>,
    ) -> Option<SVector<T, 1>> {
        if let Some(j) = jacobian {
            *j = self.h;
        }
        Some(self.h * x)
    }
    fn noise(&self, _x: &SVector<T, 8>) -> SMatrix<T, 1, 1> {
        SMatrix::<T, 1, 1>::new(self.r)
    }
}

/// The largest difference of the f32 covariance after `beams` corrections
/// (each reading's variance `ratio` times the prior's along its direction,
/// log-uniform) from the f64 one, relative to the f64 one's largest
/// entry, and the f32 one's smallest eigenvalue relative to its largest;
/// infinite and minus infinite if an f32 correction fails.
fn scan(seed: u64, update: CovarianceUpdate, beams: usize, ratio: (f64, f64)) -> (f64, f64) {
    let mut r = rng(seed);
    let a = SMatrix::<f64, 8, 8>::from_fn(|_, _| r.random_range(-1.0..1.0));
    let p0 = a * a.transpose() + SMatrix::<f64, 8, 8>::identity() * 1e-3;
    let mut b64 = Belief::new(SVector::<f64, 8>::zeros(), p0);
    let mut b32 = Belief::new(SVector::<f32, 8>::zeros(), p0.cast::<f32>());
    let (e64, e32) = (Ekf::<f64>::new(update), Ekf::<f32>::new(update));
    for _ in 0..beams {
        let h = SMatrix::<f64, 1, 8>::from_fn(|_, _| r.random_range(-1.0..1.0));
        // The reading's noise 1e-2 to 1e-4 of the prior's variance along h.
        let var = (h * b64.p * h.transpose())[(0, 0)] * log_uniform(&mut r, ratio.0, ratio.1);
        let z = r.random_range(-1.0..1.0);
        let m64 = Linear { h, r: var };
        let m32 = Linear {
            h: h.cast::<f32>(),
            r: var as f32,
        };
        b64 = e64
            .correct(&b64, &m64, &SVector::<f64, 1>::new(z))
            .unwrap()
            .belief;
        match e32.correct(&b32, &m32, &SVector::<f32, 1>::new(z as f32)) {
            Ok(c) => b32 = c.belief,
            Err(_) => return (f64::INFINITY, f64::NEG_INFINITY),
        }
    }
    let p32 = b32.p.cast::<f64>();
    let scale = b64.p.amax();
    let eig = p32.symmetric_eigenvalues();
    ((p32 - b64.p).amax() / scale, eig.min() / eig.max())
}

/// The worst `(error, smallest eigenvalue ratio)` of [`scan`] over 200
/// random scans.
fn worst(update: CovarianceUpdate, beams: usize, ratio: (f64, f64)) -> (f64, f64) {
    (0..200).fold((0.0f64, f64::INFINITY), |(e, m), seed| {
        let (err, eig) = scan(seed, update, beams, ratio);
        (e.max(err), m.min(eig))
    })
}

#[test]
fn joseph_in_f32_stays_near_f64_over_a_scan() {
    // 16 readings, each 1e-3 to 1e-1 of the variance along it. Measured:
    // Joseph 1.6e-4 (the N x N products written out: 2.4e-4), plain 3.3e-3.
    let (joseph, eig) = worst(CovarianceUpdate::Joseph, 16, (1e-3, 1e-1));
    let (plain, _) = worst(CovarianceUpdate::Plain, 16, (1e-3, 1e-1));
    println!("16 readings: Joseph {joseph:e} (smallest eigenvalue ratio {eig:e}), plain {plain:e}");
    assert!(joseph < 1e-3 && eig > 0.0, "{joseph:e} {eig:e}");
    // 30 readings, 1e-2 to 1 of it: the plain form cancels digits at each.
    // Measured: Joseph 2.0e-5 (written out: 4.0e-5), plain 4.9e-3.
    let (joseph, eig) = worst(CovarianceUpdate::Joseph, 30, (1e-2, 1.0));
    let (plain, _) = worst(CovarianceUpdate::Plain, 30, (1e-2, 1.0));
    println!("30 readings: Joseph {joseph:e} (smallest eigenvalue ratio {eig:e}), plain {plain:e}");
    assert!(joseph < 1e-4 && eig > 0.0, "{joseph:e} {eig:e}");
    assert!(joseph * 10.0 < plain, "{joseph:e} {plain:e}");
}
