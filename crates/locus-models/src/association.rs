//! Data association of paper 001: which wall does an IR observation belong to?
//!
//! From the current estimate, the IR pair's sensing ray (from the pair's
//! centre, perpendicular to the heading, to the right) is cast on the map;
//! the nearest axis-aligned segment it hits within the gate range is the wall
//! the sensors face, expressed as the [`AxisWall`] the IR model needs. The
//! observation is dropped (`None`) when the ray hits nothing within range or
//! the nearest wall is not axis-aligned (the IR model of eq. 4-5 observes
//! axis-aligned walls only).

use locus_core::nalgebra::{SVector, Vector2};
use locus_core::{Scalar, cast};

use crate::ir_wall::{AxisWall, IrPair, Side, WallAxis};
use crate::laser_wall::{BeamLimits, Segment, ray_cast};

/// Associates an IR-pair observation with a wall of `map`, or drops it.
///
/// `x` is the estimated pose `[x, y, theta]` (m, m, rad), `pair` the IR
/// mounting, `gate_range` the largest centre-of-pair-to-wall distance
/// accepted along the sensing ray (m; the sensors' useful range plus a
/// margin for the estimate's error, e.g. 0.30 + 0.10 m). A segment counts as
/// axis-aligned when its direction is within `1e-9` (relative) of an axis.
pub fn associate_ir_wall<T: Scalar>(
    x: &SVector<T, 3>,
    pair: &IrPair<T>,
    map: &[Segment<T>],
    gate_range: T,
) -> Option<AxisWall<T>> {
    let (origin, dir) = pair.sensing_ray(x);
    let hit = ray_cast(&origin, &dir, map, &BeamLimits::with_max_range(gate_range))?;
    let seg = &map[hit.segment];
    axis_wall(seg.a, seg.b, &dir)
}

/// The wall of the segment from `a` to `b` (m) as an IR pair sensing along
/// `dir` sees it: the [`AxisWall`] of its line, or `None` if the segment is
/// not axis-aligned (its direction within `1e-9`, relative, of an axis).
/// [`associate_ir_wall`] and a log's replay (which casts in its own map)
/// classify the wall they hit through it.
pub fn axis_wall<T: Scalar>(a: [T; 2], b: [T; 2], dir: &Vector2<T>) -> Option<AxisWall<T>> {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let tol = cast::<T>(1e-9) * (dx.abs() + dy.abs());
    let axis = if dx.abs() <= tol {
        WallAxis::X // vertical segment: the line x = const
    } else if dy.abs() <= tol {
        WallAxis::Y
    } else {
        return None;
    };
    let (coordinate, toward) = match axis {
        WallAxis::X => (a[0], dir[0]),
        WallAxis::Y => (a[1], dir[1]),
    };
    let side = if toward > T::zero() {
        Side::Positive
    } else {
        Side::Negative
    };
    Some(AxisWall {
        axis,
        coordinate,
        side,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::{FRAC_PI_2, PI};
    use locus_core::nalgebra::Vector3;

    /// The square arena of spec section 3 (Lw = 1 m).
    const ARENA: [Segment<f64>; 4] = [
        Segment::new([-0.85, -1.0], [0.15, -1.0]),
        Segment::new([1.0, -0.85], [1.0, 0.15]),
        Segment::new([0.85, 1.0], [-0.15, 1.0]),
        Segment::new([-1.0, 0.85], [-1.0, -0.15]),
    ];

    fn at(x: f64, y: f64, th: f64) -> Option<AxisWall<f64>> {
        associate_ir_wall(
            &Vector3::new(x, y, th),
            &IrPair::centred(0.10),
            &ARENA,
            0.40,
        )
    }

    #[test]
    fn each_leg_of_the_square_faces_its_wall() {
        // Counter-clockwise square, walls on the right.
        assert_eq!(at(-0.5, -0.85, 0.0), Some(AxisWall::y_minus(1.0)));
        assert_eq!(at(0.85, -0.5, FRAC_PI_2), Some(AxisWall::x_plus(1.0)));
        assert_eq!(at(0.5, 0.85, PI), Some(AxisWall::y_plus(1.0)));
        assert_eq!(at(-0.85, 0.5, -FRAC_PI_2), Some(AxisWall::x_minus(1.0)));
    }

    #[test]
    fn no_wall_in_range_or_off_the_segment_is_dropped() {
        // Facing y- but 0.6 m away: beyond the gate.
        assert_eq!(at(-0.5, -0.4, 0.0), None);
        // Past the end of the y- segment (x > 0.15).
        assert_eq!(at(0.5, -0.85, 0.0), None);
        // Facing away from every wall (sensors look into the arena).
        assert_eq!(at(0.0, -0.85, PI), None);
    }

    #[test]
    fn a_slanted_wall_is_dropped() {
        let map = [Segment::new([1.0, -1.0], [0.0, 1.0])];
        let pose = Vector3::new(0.3, 0.0, FRAC_PI_2);
        assert_eq!(
            associate_ir_wall(&pose, &IrPair::centred(0.10), &map, 1.0),
            None
        );
    }
}
