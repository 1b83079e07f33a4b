//! One beam of a scan against the map (papers 000 and 003: a range
//! sensor corrected one scalar at a time): the surface its cast meets, as
//! a plane ([`PlanarBeam`]) linearised at a chosen state
//! ([`LinearisedAt`]), and whether its reading can correct at all. The
//! replay's beam loop, the scan's alignment, the beams' noise estimate and
//! the truth clock judge beams through these functions, and the Intel
//! scan bench (`benches/intel_scan.rs`) times them.

use locus_core::MeasurementModel;
use locus_core::nalgebra::{SMatrix, Vector2};
use locus_models::planar_beam::{BeamMount, PlanarBeam};

pub use crate::linearised_at::LinearisedAt;
use crate::{STATE, StateMatrix, StateVector};

/// What one beam reading gives ([`beam`]).
// Returned by value once per beam and matched at once, never stored.
#[allow(clippy::large_enum_variant)]
pub enum Beam {
    /// Its cast meets no surface within range, or meets it grazing or
    /// from behind.
    NoSurface,
    /// It reads shorter than the surface by more than
    /// [`Beams::short_sigma`](crate::Beams::short_sigma) standard
    /// deviations of its innovation: something not in the map.
    Short {
        /// The innovation's variance (m^2).
        s: f64,
    },
    /// It can correct.
    Usable {
        /// The plane linearised where it was cast (its Jacobian `model.h`).
        model: LinearisedAt,
        /// The reading minus the range predicted (m).
        residual: f64,
    },
}

/// Beam `k` of `sensor`, reading `z` (m), cast in `map` from the state
/// `from` and linearised there ([`LinearisedAt`]), then judged at the
/// state `x` of covariance `p`: the surface it meets ([`beam_model`]), the
/// range predicted at `x` and whether the reading is far too short for it.
/// The beam loop (`scan_correct`: `from` the scan's alignment, else `x`)
/// and the scan's alignment (`scan_align.rs`: `from` and `x` its iterate)
/// judge a beam alike through it.
#[allow(clippy::too_many_arguments)]
pub fn beam(
    map: &locus_map::Map,
    sensor: &locus_logs::BeamSensor,
    k: usize,
    z: f64,
    from: &StateVector,
    x: &StateVector,
    p: &StateMatrix,
    beams: &crate::Beams,
) -> Beam {
    match beam_model(map, sensor, k, from, beams) {
        Some(planar) => judge(&planar, z, from, x, p, beams),
        None => Beam::NoSurface,
    }
}

/// The plane `planar` a beam reading `z` (m) met, linearised at the state
/// `from` ([`LinearisedAt`]) and judged at the state `x` of covariance
/// `p`: the second half of [`beam`], after its cast.
pub fn judge(
    planar: &PlanarBeam<f64>,
    z: f64,
    from: &StateVector,
    x: &StateVector,
    p: &StateMatrix,
    beams: &crate::Beams,
) -> Beam {
    let mut h = SMatrix::<f64, 1, STATE>::zeros();
    let Some(h0) = planar.evaluate(from, Some(&mut h)) else {
        return Beam::NoSurface;
    };
    let model = LinearisedAt {
        h0: h0[0],
        h,
        at: *from,
        var: planar.var_range,
    };
    let Some(predicted) = model.h(x) else {
        return Beam::NoSurface;
    };
    let s = (h * p * h.transpose())[(0, 0)] + model.var;
    let residual = z - predicted[0];
    if residual < -beams.short_sigma * s.sqrt() {
        return Beam::Short { s };
    }
    Beam::Usable { model, residual }
}

/// Beam `k` of `sensor` at the state `x`: cast in `map` from the sensor,
/// the surface it meets (within the sensor's range, at an incidence of at
/// most `beams.max_incidence`) as a [`PlanarBeam`]; `None` where it meets
/// none.
pub fn beam_model(
    map: &locus_map::Map,
    sensor: &locus_logs::BeamSensor,
    k: usize,
    x: &StateVector,
    beams: &crate::Beams,
) -> Option<PlanarBeam<f64>> {
    let (sin, cos) = x[2].sin_cos();
    let m = sensor.mount;
    let origin = [x[0] + cos * m.x - sin * m.y, x[1] + sin * m.x + cos * m.y];
    let angle_on_robot = m.yaw + sensor.angle(u32::try_from(k).unwrap_or(u32::MAX));
    let hit = map
        .cast(origin, x[2] + angle_on_robot, sensor.max_range)
        .filter(|h| h.incidence <= beams.max_incidence)?;
    Some(PlanarBeam {
        mount: BeamMount {
            position: Vector2::new(m.x, m.y),
            angle: angle_on_robot,
        },
        point: Vector2::new(hit.point[0], hit.point[1]),
        normal: Vector2::new(hit.normal[0], hit.normal[1]),
        var_range: beams.sigma * beams.sigma,
        min_range: sensor.min_range,
        max_incidence: beams.max_incidence,
    })
}
