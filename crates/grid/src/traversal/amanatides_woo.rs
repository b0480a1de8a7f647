//! Amanatides & Woo (1987) 3DDDA in floating point.
//!
//! Per axis: `t_max` (the `t` of the next wall crossing); each step moves along the axis with
//! the smallest `t_max` and advances that axis' crossing. The survey's incremental update
//! `t_max += t_delta` accumulates one rounding per step (up to ~0.01 cell after a thousand steps
//! from a distant origin), so this implementation evaluates the same quantity from the integer
//! wall index, `t_max = (wall − o) · (1/d)`: no drift, same comparisons, and a form no shader
//! compiler can contract into an FMA, so the WGSL port takes exactly the same steps.

use glam::{UVec3, Vec3};

use super::{CellStep, Cursor, argmin3};
use crate::geometry::GridRay;

#[derive(Clone, Debug)]
pub struct AmanatidesWoo {
    pub(super) cur: Cursor,
    /// Next wall index per axis (as f32: exact for any resolution ≤ 2^24).
    wall: Vec3,
    o: Vec3,
    inv_d: Vec3,
    t_max: Vec3,
    t1: f32,
}

impl AmanatidesWoo {
    pub fn new(ray: &GridRay, res: UVec3) -> AmanatidesWoo {
        let cur = Cursor::start(ray, res);
        let mut wall = Vec3::ZERO;
        let mut t_max = Vec3::INFINITY;
        for a in 0..3 {
            if ray.d[a] != 0.0 {
                wall[a] = cur.wall(a);
                t_max[a] = (wall[a] - ray.o[a]) * ray.inv_d[a];
            }
        }
        AmanatidesWoo { cur, wall, o: ray.o, inv_d: ray.inv_d, t_max, t1: ray.t1 }
    }

    /// The current cell and its exit; then the next crossing (the cursor is not done).
    #[inline]
    pub(super) fn advance(&mut self) -> Option<CellStep> {
        let a = argmin3(self.t_max.to_array());
        let t = self.t_max[a];
        let out = CellStep { cell: self.cur.cell.as_uvec3(), t_exit: t.min(self.t1) };
        if t.is_nan() || t > self.t1 {
            // The segment ends inside this cell.
            self.cur.done = true;
        } else {
            self.cur.cross(a);
            self.wall[a] += self.cur.step[a] as f32;
            self.t_max[a] = (self.wall[a] - self.o[a]) * self.inv_d[a];
        }
        Some(out)
    }
}
