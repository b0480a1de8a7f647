//! Integer one-pass traversal after Liu, Zhang & Yang (2004), extended to 3-D.
//!
//! Like Bresenham, the walk advances one slice of the driving axis `u` (largest |direction|) at
//! a time. Unlike Bresenham, it also visits the cells where the line crosses a wall of a minor
//! axis (`v`, `w`) inside the slice: the minor coordinates at the end of each slice are kept
//! in fixed point (20 fractional bits, i32) and advanced by the fixed-point slope `K = d_v/d_u`
//! with one integer add per slice. When both minor axes cross inside a slice, the one whose
//! wall lies farther back from the slice end (overshoot / slope: Liu's threshold test,
//! compared exactly by 64-bit cross-multiplication) is crossed first.
//!
//! Error: the slope is rounded once (≤ 2^-21 cell), so after the at most
//! [`MAX_AXIS_RES`](crate::geometry::MAX_AXIS_RES) = 1024 slices the minor coordinates are off
//! by ≤ 5e-4 cell, well inside the insertion margin. The `t` where the ray leaves each cell
//! is computed geometrically from the cell index ([`GridRay::exit_of_cell`]).

use glam::{IVec3, UVec3};

use super::{CellStep, Cursor};
use crate::geometry::GridRay;
use crate::ray::argmax3;

/// Fractional bits of the fixed-point minor coordinates.
pub const FRAC_BITS: u32 = 20;
const ONE: f32 = (1u32 << FRAC_BITS) as f32;

#[derive(Clone, Debug)]
pub struct Liu {
    ray: GridRay,
    /// Axis permutation: driving axis, then the two minor axes.
    u: usize,
    v: usize,
    w: usize,
    pub(super) cur: Cursor,
    /// Slices still to enter after the current one.
    slices_left: i32,
    /// Fixed-point change of (v, w) per slice: d_v / |d_u|, d_w / |d_u|.
    k: [i32; 2],
    /// Fixed-point minor coordinates (v, w) at the end of the current slice.
    end: [i32; 2],
    /// Fixed-point minor coordinates at the segment's end point.
    last: [i32; 2],
    /// Cells of the current slice still to emit (a slice yields 1 to 3 cells, more only when
    /// the start lies exactly on walls).
    queue: [IVec3; 8],
    queued: usize,
    emitted: usize,
}

#[inline]
fn fix(x: f32, hi: i32) -> i32 {
    // Clamp first: a segment end a hair outside the grid must not overflow i32.
    // floor(x + 0.5), not round(): WGSL's round() ties to even, Rust's away from zero.
    (x.clamp(-1.0, hi as f32 + 1.0) * ONE + 0.5).floor() as i32
}

/// The cell a fixed-point coordinate lies in when moving in direction `s` (a point exactly on
/// a wall belongs to the cell the line is entering).
#[inline]
fn cell_of(x: i32, s: i32) -> i32 {
    if s >= 0 { x >> FRAC_BITS } else { -((-x) >> FRAC_BITS) - 1 }
}

impl Liu {
    pub fn new(ray: &GridRay, res: UVec3) -> Liu {
        let ad = ray.d.abs();
        let u = argmax3(ad.to_array());
        let (v, w) = ((u + 1) % 3, (u + 2) % 3);
        let res_i = res.as_ivec3();
        let mut cur = Cursor::start(ray, res);
        let start = cur.cell;
        let end_cell = ray.end_cell(res).as_ivec3();
        let p0 = ray.o + ray.d * ray.t0;
        let p1 = ray.o + ray.d * ray.t1;
        let su = if cur.step[u] == 0 { 1 } else { cur.step[u] };
        cur.step[u] = su;
        let slices_left = ((end_cell[u] - start[u]) * su).max(0);
        // d_a · (1/d_u) rather than d_a / d_u: the WGSL port computes the same product (a GPU
        // division need not be correctly rounded, a reciprocal times a product is the same).
        let kf = |a: usize| if ray.d[u] != 0.0 { ray.d[a] * ray.inv_d[u] } else { 0.0 };
        // Per slice the driving coordinate moves by su, so the minor ones move by su·d_a/d_u.
        let k = [fix_slope(kf(v) * su as f32), fix_slope(kf(w) * su as f32)];
        let last = [fix(p1[v], res_i[v]), fix(p1[w], res_i[w])];
        let end = if slices_left == 0 {
            last
        } else {
            let du = cur.wall(u) - p0[u];
            [fix(p0[v] + du * kf(v), res_i[v]), fix(p0[w] + du * kf(w), res_i[w])]
        };
        let mut liu =
            Liu { ray: *ray, u, v, w, cur, slices_left, k, end, last, queue: [IVec3::ZERO; 8], queued: 0, emitted: 0 };
        liu.fill_slice();
        liu
    }

    /// Queues the cells of the current slice: the cell the slice starts in, then one cell per
    /// minor-wall crossing, in crossing order.
    fn fill_slice(&mut self) {
        let (v, w) = (self.v, self.w);
        let Cursor { step, res, .. } = self.cur;
        self.queue[0] = self.cur.cell;
        self.queued = 1;
        self.emitted = 0;
        let (sv, sw) = (step[v], step[w]);
        let target = |x: i32, s: i32, c: i32, hi: i32| {
            if s == 0 {
                return c;
            }
            let t = cell_of(x, s).clamp(0, hi - 1);
            // Never walk backwards (a rounding artefact at the very start).
            if (t - c) * s < 0 { c } else { t }
        };
        let tv = target(self.end[0], sv, self.cur.cell[v], res[v]);
        let tw = target(self.end[1], sw, self.cur.cell[w], res[w]);
        while (self.cur.cell[v] != tv || self.cur.cell[w] != tw) && self.queued < self.queue.len() {
            let cell = &mut self.cur.cell;
            let move_v = if cell[v] == tv {
                false
            } else if cell[w] == tw {
                true
            } else {
                // Overshoot past the next wall at the slice end, divided by the slope, is how
                // far before the slice end the wall was crossed: the larger one comes first.
                let wall_v = (cell[v] + (sv > 0) as i32) << FRAC_BITS;
                let wall_w = (cell[w] + (sw > 0) as i32) << FRAC_BITS;
                // Exact 64-bit products (the WGSL port multiplies wide in u32 halves).
                let ev = (self.end[0] - wall_v).unsigned_abs() as u64;
                let ew = (self.end[1] - wall_w).unsigned_abs() as u64;
                ev * self.k[1].unsigned_abs() as u64 >= ew * self.k[0].unsigned_abs() as u64
            };
            if move_v {
                cell[v] += sv;
            } else {
                cell[w] += sw;
            }
            self.queue[self.queued] = *cell;
            self.queued += 1;
        }
    }

    /// Moves into the next slice of the driving axis; false when the segment has ended.
    fn next_slice(&mut self) -> bool {
        if self.slices_left == 0 {
            return false;
        }
        self.slices_left -= 1;
        self.cur.cross(self.u);
        if self.cur.done {
            return false;
        }
        if self.slices_left == 0 {
            self.end = self.last;
        } else {
            self.end[0] += self.k[0];
            self.end[1] += self.k[1];
        }
        self.fill_slice();
        true
    }
}

#[inline]
fn fix_slope(k: f32) -> i32 {
    (k.clamp(-1.0, 1.0) * ONE + 0.5).floor() as i32
}

impl Liu {
    /// The next queued cell, moving into the next slice when the queue is empty (the cursor is
    /// not done).
    #[inline]
    pub(super) fn advance(&mut self) -> Option<CellStep> {
        if self.emitted == self.queued && !self.next_slice() {
            self.cur.done = true;
            return None;
        }
        let c = self.queue[self.emitted].as_uvec3();
        self.emitted += 1;
        Some(CellStep { cell: c, t_exit: self.ray.exit_of_cell(c) })
    }
}
