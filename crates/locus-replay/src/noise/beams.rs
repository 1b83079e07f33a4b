//! The beams' noise from a round's smoothed scans (see the parent module).

use super::*;

/// What a round keeps of each smoothed scan.
pub(super) struct KeptScan {
    pub(super) index: usize,
    pub(super) state: SVector<f64, STATE>,
    pub(super) covariance: locus_core::nalgebra::Matrix3<f64>,
}

/// The state of a smoothed pose `x` and calibration `c`.
pub(super) fn smoothed_state(
    x: &locus_core::nalgebra::Vector3<f64>,
    c: &[f64; 4],
) -> SVector<f64, STATE> {
    let mut state = SVector::<f64, STATE>::zeros();
    for i in 0..3 {
        state[i] = x[i];
    }
    for i in 0..4 {
        state[3 + i] = c[i];
    }
    state
}

/// The beams' noise from the smoothed scans: each chosen beam with a
/// reading, cast in the map from the smoothed pose, gives a residual
/// (reading minus the range to the surface); their robust spread with the
/// smoother's own uncertainty (`H Ps H^T`), and their autocorrelation time
/// from scan to scan per beam ([`batch_tau`], each beam a series).
/// Returns `(spread m, tau, residuals)`; NaN and 1 without any.
#[allow(clippy::cast_precision_loss)]
pub(super) fn beam_noise(log: &Log, cfg: &Config, scans: &[KeptScan]) -> (f64, f64, usize) {
    use locus_logs::scans::Reading;
    let Some(map) = log.map.as_deref() else {
        return (f64::NAN, 1.0, 0);
    };
    let mut residuals = Vec::new();
    let mut hph = 0.0;
    for k in scans {
        let Some(scan) = log.scans.get(k.index) else {
            continue;
        };
        let Some(sensor) = log.beam_sensors.iter().find(|b| b.id == scan.sensor) else {
            continue;
        };
        for b in crate::filter::chosen_beams(scan.ranges.len(), cfg.beams.per_scan) {
            let Reading::Range(z) = Reading::of(scan.ranges[b]) else {
                continue;
            };
            let Some(model) = crate::beam::beam_model(map, sensor, b, &k.state, &cfg.beams) else {
                continue;
            };
            let Some(h) = model.h(&k.state) else { continue };
            let j = model
                .jacobian(&k.state)
                .fixed_view::<1, 3>(0, 0)
                .into_owned();
            hph += (j * k.covariance * j.transpose())[(0, 0)];
            // One series per sensor and beam.
            let series = scan.sensor.wrapping_mul(1 << 17).wrapping_add(b as u32);
            residuals.push((series, scan.time, f64::from(z) - h[0]));
        }
    }
    if residuals.is_empty() {
        return (f64::NAN, 1.0, 0);
    }
    let n = residuals.len() as f64;
    let spread = robust_spread(residuals.iter().map(|r| r.2).collect()).hypot((hph / n).sqrt());
    let tau = batch_tau(&residuals, spread);
    (spread, tau, residuals.len())
}
