//! Naive 3-D Bresenham line from the segment's first cell to its last: **incomplete by
//! design** (survey §2, Figure 1). It steps the driving axis one cell at a time and moves each
//! minor axis at most once per step, so it visits exactly one cell per slice and skips the
//! cells where the ray crosses a minor wall between two slices. It is here to measure that.

use glam::{IVec3, UVec3};

use super::CellStep;
use crate::geometry::GridRay;
use crate::ray::argmax3;

#[derive(Clone, Debug)]
pub struct Bresenham {
    ray: GridRay,
    cell: IVec3,
    step: IVec3,
    /// 2·|Δ| per axis.
    two_delta: IVec3,
    /// Error terms of the minor axes.
    err: IVec3,
    u: usize,
    /// Cells left to emit, the current one included.
    left: i32,
}

impl Bresenham {
    pub fn new(ray: &GridRay, res: UVec3) -> Bresenham {
        let a = ray.start_cell(res).as_ivec3();
        let b = ray.end_cell(res).as_ivec3();
        let delta = b - a;
        let ad = delta.abs();
        let u = argmax3(ad.to_array());
        let n = ad[u];
        // Classic decision variable D = 2·Δminor − Δmajor.
        let err = ad * 2 - IVec3::splat(n);
        Bresenham { ray: *ray, cell: a, step: delta.signum(), two_delta: ad * 2, err, u, left: n + 1 }
    }
}

impl Iterator for Bresenham {
    type Item = CellStep;
    fn next(&mut self) -> Option<CellStep> {
        if self.left <= 0 {
            return None;
        }
        self.left -= 1;
        let c = self.cell.as_uvec3();
        let out = CellStep { cell: c, t_exit: self.ray.exit_of_cell(c) };
        if self.left > 0 {
            let u = self.u;
            let n2 = self.two_delta[u];
            for a in 0..3 {
                if a == u {
                    continue;
                }
                if self.err[a] > 0 {
                    self.cell[a] += self.step[a];
                    self.err[a] -= n2;
                }
                self.err[a] += self.two_delta[a];
            }
            self.cell[u] += self.step[u];
        }
        Some(out)
    }
}
