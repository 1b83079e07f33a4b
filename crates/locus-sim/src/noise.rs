//! The simulator's Gaussian draws: every scenario and sensor takes its
//! zero-mean normal noise from [`gauss`], so a standard deviation is
//! applied the same way everywhere and the random stream of a run depends
//! only on the number of draws.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// A draw from `N(0, std^2)`: one standard normal sample from `rng`, times
/// `std`. Always draws exactly one value, whatever `std` (even 0), so a
/// noise level never shifts the random stream of what is drawn after it.
pub(crate) fn gauss<R: Rng + ?Sized>(rng: &mut R, std: f64) -> f64 {
    let n: f64 = StandardNormal.sample(rng);
    std * n
}
