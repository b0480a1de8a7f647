//! Cleary & Wyvill (1988): the next cell from two or three integer operations.
//!
//! Distances along the ray to the next wall crossing of each axis (`dist`) and between
//! crossings (`delta`) are kept in 32-bit fixed point over the clipped segment: the segment
//! `[t0, t1]` maps to `[0, 2^30]`. Each step picks the smallest distance, adds that axis'
//! `delta` (an exact integer add, so unlike a float accumulation nothing drifts: the only
//! error is the one-time rounding of `delta`, ≤ 2^-31 of the segment per step), and moves the
//! linear cell address by that axis' stride. The walk ends when the next crossing lies beyond
//! the segment. (The original omits index bounds checks; one is kept here as a guard against a
//! rounding-induced step through the exit face.)

use glam::{IVec3, UVec3};

use super::{CellStep, Cursor, argmin3};
use crate::geometry::GridRay;

/// Fixed-point length of the clipped segment.
pub const SCALE: u32 = 1 << 30;
/// One fixed-point unit, 2^-30 of the segment.
const UNIT: f32 = 1.0 / SCALE as f32;
/// "Beyond the segment": never reached by a crossing inside it.
pub const BEYOND: u32 = SCALE + 1;

#[derive(Clone, Debug)]
pub struct ClearyWyvill {
    pub(super) cur: Cursor,
    stride: IVec3,
    address: i32,
    dist: [u32; 3],
    delta: [u32; 3],
    t0: f32,
    t1: f32,
    /// `1 / (t1 − t0)`: the fixed-point units per unit of `t` are this times 2^30, applied in
    /// two steps (equal to one product with `2^30 / seg` wherever that is finite, since scaling
    /// by 2^30 is exact), so that a segment shorter than 2^-98 (a huge direction: 1e30 over a
    /// unit grid) does not overflow them and turn the walk into its first cell.
    inv_seg: f32,
}

impl ClearyWyvill {
    pub fn new(ray: &GridRay, res: UVec3) -> ClearyWyvill {
        let mut cur = Cursor::start(ray, res);
        let c = cur.cell;
        let seg = ray.t1 - ray.t0;
        let inv_seg = 1.0 / seg;
        let single = seg.is_nan() || seg <= 0.0 || !inv_seg.is_finite();
        let mut dist = [BEYOND; 3];
        let mut delta = [BEYOND; 3];
        for a in 0..3 {
            if ray.d[a] == 0.0 || single {
                cur.step[a] = 0;
                continue;
            }
            let t_cross = (cur.wall(a) - ray.o[a]) * ray.inv_d[a];
            dist[a] = to_fixed(((t_cross - ray.t0) * inv_seg) * SCALE as f32);
            delta[a] = to_fixed((ray.inv_d[a].abs() * inv_seg) * SCALE as f32).max(1);
        }
        let stride = IVec3::new(1, res.x as i32, (res.x * res.y) as i32);
        ClearyWyvill { cur, stride, address: c.dot(stride), dist, delta, t0: ray.t0, t1: ray.t1, inv_seg }
    }

    /// The current cell and its exit; then the next crossing (the cursor is not done).
    #[inline]
    pub(super) fn advance(&mut self) -> Option<CellStep> {
        let a = argmin3(self.dist);
        let d = self.dist[a];
        let t_exit = if d >= SCALE { self.t1 } else { self.t0 + (d as f32 * UNIT) / self.inv_seg };
        let out = CellStep { cell: self.cur.cell.as_uvec3(), t_exit };
        if d > SCALE {
            self.cur.done = true;
        } else {
            self.cur.cross(a);
            self.address += self.stride[a] * self.cur.step[a];
            self.dist[a] = (self.dist[a] + self.delta[a]).min(BEYOND);
        }
        Some(out)
    }

    /// Linear index of the current cell (x fastest), maintained incrementally.
    pub fn address(&self) -> i32 {
        self.address
    }
}

/// f32 → fixed point, saturating to [0, BEYOND].
#[inline]
fn to_fixed(x: f32) -> u32 {
    if x >= BEYOND as f32 {
        BEYOND
    } else if x > 0.0 {
        x as u32
    } else {
        0
    }
}
