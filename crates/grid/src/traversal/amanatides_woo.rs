//! Amanatides & Woo (1987) 3DDDA in floating point.
//!
//! Per axis: `t_max` (the `t` of the next wall crossing) and `t_delta` (the `t` between two
//! crossings); each step moves along the axis with the smallest `t_max`. The survey's
//! incremental update `t_max += t_delta` accumulates one rounding per step (up to ~0.01 cell
//! after a thousand steps from a distant origin), so this implementation evaluates the same
//! quantity as `t_max0 + n · t_delta` with `n` the step count on that axis: two roundings,
//! no drift, same comparisons.

use glam::{IVec3, UVec3, Vec3};

use super::{CellStep, argmin3};
use crate::geometry::GridRay;

#[derive(Clone, Debug)]
pub struct AmanatidesWoo {
    cell: IVec3,
    step: IVec3,
    res: IVec3,
    t_max0: Vec3,
    t_delta: Vec3,
    n: Vec3,
    t_max: Vec3,
    t1: f32,
    done: bool,
}

impl AmanatidesWoo {
    pub fn new(ray: &GridRay, res: UVec3) -> AmanatidesWoo {
        let c = ray.start_cell(res);
        let mut step = IVec3::ZERO;
        let mut t_max0 = Vec3::INFINITY;
        let mut t_delta = Vec3::ZERO;
        for a in 0..3 {
            if ray.d[a] > 0.0 {
                step[a] = 1;
                t_max0[a] = (c[a] as f32 + 1.0 - ray.o[a]) * ray.inv_d[a];
                t_delta[a] = ray.inv_d[a];
            } else if ray.d[a] < 0.0 {
                step[a] = -1;
                t_max0[a] = (c[a] as f32 - ray.o[a]) * ray.inv_d[a];
                t_delta[a] = -ray.inv_d[a];
            }
        }
        AmanatidesWoo {
            cell: c.as_ivec3(),
            step,
            res: res.as_ivec3(),
            t_max0,
            t_delta,
            n: Vec3::ZERO,
            t_max: t_max0,
            t1: ray.t1,
            done: false,
        }
    }
}

impl Iterator for AmanatidesWoo {
    type Item = CellStep;
    #[inline]
    fn next(&mut self) -> Option<CellStep> {
        if self.done {
            return None;
        }
        let a = argmin3(self.t_max.to_array());
        let t = self.t_max[a];
        let out = CellStep { cell: self.cell.as_uvec3(), t_exit: t.min(self.t1) };
        if t.is_nan() || t > self.t1 {
            // The segment ends inside this cell.
            self.done = true;
        } else {
            self.cell[a] += self.step[a];
            if self.cell[a] < 0 || self.cell[a] >= self.res[a] {
                self.done = true;
            }
            self.n[a] += 1.0;
            self.t_max[a] = self.t_max0[a] + self.n[a] * self.t_delta[a];
        }
        Some(out)
    }
}
