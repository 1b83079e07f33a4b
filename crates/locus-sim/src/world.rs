//! The simulated world: a set of wall segments (m, world frame) and ray casts
//! against them.
//!
//! Ray casting is [`locus_models::laser_wall::ray_cast`], the same routine the
//! exact laser model uses, so the simulator and the filter agree on geometry.

use locus_core::nalgebra::{Vector2, Vector3};
use locus_models::laser_wall::{BeamLimits, LaserMount, Segment, ray_cast};

use crate::robot::Pose;

/// Half-length (m) of the "long" wall of [`World::wall45`] on each side of its
/// crossing with the x axis.
pub const WALL45_HALF_LENGTH: f64 = 100.0;

/// Half-side of the square arena of seed 001, `Lw` (m, \[assumed\] spec
/// section 3).
pub const ARENA_LW: f64 = 1.0;

/// Where a beam hit the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Range along the beam from its origin (m), in `(0, max_range]`.
    pub range: f64,
    /// Index of the wall hit in [`World::walls`].
    pub wall_index: usize,
    /// The hit point (m, world frame).
    pub point: [f64; 2],
}

/// A 2-D world of straight wall segments (m, world frame).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct World {
    /// The walls. A zero-length segment is never hit.
    pub walls: Vec<Segment<f64>>,
}

impl World {
    /// A world with the given walls.
    pub fn new(walls: Vec<Segment<f64>>) -> Self {
        Self { walls }
    }

    /// A world with no walls (every ray cast returns `None`).
    pub fn empty() -> Self {
        Self::default()
    }

    /// The square arena of seed 001 (spec section 3, \[assumed\] `Lw = 1.0 m`):
    /// four wall segments covering the first metre of each side of the robot's
    /// counter-clockwise square path, in this order (indices 0..4):
    ///
    /// | index | wall | from | to |
    /// |---|---|---|---|
    /// | 0 | y- | (-0.85, -1) | (0.15, -1) |
    /// | 1 | x+ | (1, -0.85) | (1, 0.15) |
    /// | 2 | y+ | (0.85, 1) | (-0.15, 1) |
    /// | 3 | x- | (-1, 0.85) | (-1, -0.15) |
    pub fn square_arena() -> Self {
        let lw = ARENA_LW;
        Self::new(vec![
            Segment::new([-0.85, -lw], [0.15, -lw]),
            Segment::new([lw, -0.85], [lw, 0.15]),
            Segment::new([0.85, lw], [-0.15, lw]),
            Segment::new([-lw, 0.85], [-lw, -0.15]),
        ])
    }

    /// The single wall of seed 000 (spec section 2): the line `x + y = a`
    /// (`a` in m; test value 1.17), as one segment from
    /// `(a - h, h)` to `(a + h, -h)` with `h =` [`WALL45_HALF_LENGTH`].
    pub fn wall45(a: f64) -> Self {
        let h = WALL45_HALF_LENGTH;
        Self::new(vec![Segment::new([a - h, h], [a + h, -h])])
    }

    /// Casts a ray from `origin` (m, world frame) at `angle` (rad, world frame,
    /// counter-clockwise from the x axis) and returns the nearest wall hit
    /// with `0 < range <= max_range` (m), or `None`. A beam parallel to a wall
    /// (within [`locus_models::laser_wall::DEFAULT_PARALLEL_TOL`]) does not
    /// hit it; on a tie the lower wall index wins.
    pub fn raycast(&self, origin: [f64; 2], angle: f64, max_range: f64) -> Option<Hit> {
        let (s, c) = angle.sin_cos();
        let p = Vector2::new(origin[0], origin[1]);
        let u = Vector2::new(c, s);
        let limits = BeamLimits::with_max_range(max_range);
        ray_cast(&p, &u, &self.walls, &limits).map(|r| Hit {
            range: r.hit.range,
            wall_index: r.segment,
            point: [r.hit.point[0], r.hit.point[1]],
        })
    }

    /// Casts the beam of a sensor mounted at `mount` on a robot at `pose`
    /// (the sensor's world position and beam direction as in
    /// [`LaserMount::sensor_position`] and [`LaserMount::beam_direction`]).
    pub fn raycast_mount(
        &self,
        pose: &Pose<f64>,
        mount: &LaserMount<f64>,
        max_range: f64,
    ) -> Option<Hit> {
        let x = Vector3::new(pose.x, pose.y, pose.theta);
        let p = mount.sensor_position(&x);
        self.raycast([p[0], p[1]], pose.theta + mount.beta, max_range)
    }
}
