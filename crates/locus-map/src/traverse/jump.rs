//! The cell traversal that jumps over empty space: `Traversal::first` read
//! through the grid's clearance (`clearance.rs`), for the grid cast.
//!
//! In a cell of clearance `c`, no cell within `c - 1` columns and rows is
//! occupied, so the ray may take `c - 1` steps along each axis unread. The
//! jump must land exactly where the step-by-step traversal would be, with the
//! same ray parameters to the bit, or the hit's range would differ in its
//! last bits: the traversal's next crossing times along an axis are running
//! sums (`t_max_x += t_delta_x`, one addition a step), so a jump repeats
//! those additions, axis by axis, rather than multiplying. What it saves is
//! the step-by-step traversal's branch on which axis steps next (it
//! mispredicts along diagonals) and its reads: each axis's additions form a
//! chain of their own, and which cell the ray is in after `n` steps along
//! one axis follows from one comparison per step along the other.
//!
//! The order of the steps is the merge of the two axes' crossing times, an
//! x step first when its time is strictly earlier (`t_max_x < t_max_y`).
//! After `n` x steps, the last at time `tx`, the ray has taken every y step
//! whose time is at most `tx`; after `n` y steps, the last at `ty`, every x
//! step whose time is earlier than `ty`. A jump takes `c - 1` steps along
//! the axis that steps more often (the other then takes at most about as
//! many); if the other takes more than `c - 1`, it takes `c - 1` along the
//! other axis instead (the first axis then takes fewer); a jump that neither
//! bounds (only where the sums stop growing, far outside any map) is not
//! taken, and the ray steps cell by cell.

use super::{Traversal, Visit};
use crate::bits::OccupiedBits;
use crate::clearance::Clearance;

/// The least clearance the traversal jumps from; from cells of less it steps
/// one cell at a time.
const MIN_JUMP: u8 = 3;

/// Where a jump lands: the steps along each axis, the ray parameter where it
/// enters the cell it lands in, the next crossing time along each axis, and
/// whether its last step was along x.
struct Jump {
    steps_x: i64,
    steps_y: i64,
    t: f64,
    t_max_x: f64,
    t_max_y: f64,
    last_x: bool,
}

/// `n` (at least 1) steps along x from next crossing times `t_max_x`,
/// `t_max_y` (spacing `dt_x`, `dt_y`) and the y steps taken meanwhile, if
/// they are at most `n`.
#[inline]
fn along_x(t_max_x: f64, t_max_y: f64, dt_x: f64, dt_y: f64, n: i64) -> Option<Jump> {
    let mut tx = t_max_x;
    for _ in 1..n {
        tx += dt_x;
    }
    let (mut ty, mut steps_y) = (t_max_y, 0);
    while ty <= tx {
        if steps_y == n {
            return None;
        }
        ty += dt_y;
        steps_y += 1;
    }
    Some(Jump {
        steps_x: n,
        steps_y,
        t: tx,
        t_max_x: tx + dt_x,
        t_max_y: ty,
        last_x: true,
    })
}

/// `n` (at least 1) steps along y and the x steps taken meanwhile, if they
/// are at most `n`: [`along_x`] with the axes swapped, ties going to y.
#[inline]
fn along_y(t_max_x: f64, t_max_y: f64, dt_x: f64, dt_y: f64, n: i64) -> Option<Jump> {
    let mut ty = t_max_y;
    for _ in 1..n {
        ty += dt_y;
    }
    let (mut tx, mut steps_x) = (t_max_x, 0);
    while tx < ty {
        if steps_x == n {
            return None;
        }
        tx += dt_x;
        steps_x += 1;
    }
    Some(Jump {
        steps_x,
        steps_y: n,
        t: ty,
        t_max_x: tx,
        t_max_y: ty + dt_y,
        last_x: false,
    })
}

impl Traversal {
    /// The first cell, nearest first, that `bits` (the grid's occupied
    /// cells, row-major) marks occupied: the visit `self.first(|k|
    /// bits.get(k))` returns, to the bit, jumping over cells that
    /// `clearance` (of the same grid, or of one with more cells occupied)
    /// says cannot be occupied. Allocates nothing.
    #[inline]
    pub fn first_clear(self, bits: &OccupiedBits, clearance: &Clearance) -> Option<Visit> {
        if self.done {
            return None;
        }
        let w = self.width;
        let mut k = self.iy * w + self.ix;
        let steps_left = |i: i64, step: i64, n: i64| match step {
            1 => n - 1 - i,
            -1 => i,
            _ => i64::MAX,
        };
        let mut left_x = steps_left(self.ix, self.step_x, w);
        let mut left_y = steps_left(self.iy, self.step_y, self.height);
        let (dk_x, dk_y) = (self.step_x, self.step_y * w);
        let (dt_x, dt_y) = (self.t_delta_x, self.t_delta_y);
        let (mut t_max_x, mut t_max_y, mut t) = (self.t_max_x, self.t_max_y, self.t);
        let mut last_x: Option<bool> = None;
        // Jumps need an axis that steps; the one that steps more often
        // bounds them first.
        let can_jump = dt_x.min(dt_y).is_finite();
        let x_first = dt_x <= dt_y;
        loop {
            let c = clearance.get(k as usize);
            if c >= MIN_JUMP && can_jump {
                let n = i64::from(c - 1);
                let jump = if x_first {
                    along_x(t_max_x, t_max_y, dt_x, dt_y, n)
                        .or_else(|| along_y(t_max_x, t_max_y, dt_x, dt_y, n))
                } else {
                    along_y(t_max_x, t_max_y, dt_x, dt_y, n)
                        .or_else(|| along_x(t_max_x, t_max_y, dt_x, dt_y, n))
                };
                if let Some(j) = jump {
                    // Every step taken was at or before `j.t`, every cell
                    // passed free: past the limit or out of the grid there,
                    // the ray met nothing.
                    if j.t > self.t_end {
                        return None;
                    }
                    left_x -= j.steps_x;
                    left_y -= j.steps_y;
                    if (left_x | left_y) < 0 {
                        return None;
                    }
                    k += j.steps_x * dk_x + j.steps_y * dk_y;
                    (t, t_max_x, t_max_y) = (j.t, j.t_max_x, j.t_max_y);
                    last_x = Some(j.last_x);
                    continue;
                }
            }
            if c == 0 && bits.get(k as usize) {
                break;
            }
            // One step, as `first`.
            let x = t_max_x < t_max_y;
            let t_next = if x { t_max_x } else { t_max_y };
            if t_next > self.t_end {
                return None;
            }
            t = t_next;
            if x {
                t_max_x += dt_x;
                k += dk_x;
                left_x -= 1;
            } else {
                t_max_y += dt_y;
                k += dk_y;
                left_y -= 1;
            }
            last_x = Some(x);
            if (left_x | left_y) < 0 {
                return None;
            }
        }
        let face = match last_x {
            None => self.face,
            Some(true) => Some([-(self.step_x as f64), 0.0]),
            Some(false) => Some([0.0, -(self.step_y as f64)]),
        };
        Some(Visit {
            ix: (k % w) as usize,
            iy: (k / w) as usize,
            t_enter: t,
            t_exit: t_max_x.min(t_max_y).min(self.t_end),
            face,
        })
    }
}
