//! Amanatides & Woo (1987) 3DDDA in floating point.
//!
//! Per axis: `t_max` (the `t` of the next wall crossing); each step moves along the axis with
//! the smallest `t_max` and advances that axis' crossing. The survey's incremental update
//! `t_max += t_delta` accumulates one rounding per step (up to ~0.01 cell after a thousand steps
//! from a distant origin), so this implementation evaluates the same quantity from the integer
//! wall index, `t_max = (wall − o) · (1/d)`: no drift, same comparisons, and a form no shader
//! compiler can contract into an FMA, so the WGSL port takes exactly the same steps.

use glam::{IVec3, UVec3, Vec3};

use super::{CellStep, Cursor, argmin3};
use crate::geometry::{GridRay, linear_index};

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
        // On the axes the ray moves along, the next wall and its crossing; elsewhere 0 and
        // never. Selected, not branched on: a random ray's direction signs are unpredictable.
        let moving = ray.d.cmpne(Vec3::ZERO);
        let wall = Vec3::select(moving, Vec3::from_array(std::array::from_fn(|a| cur.wall(a))), Vec3::ZERO);
        let t_max = Vec3::select(moving, (wall - ray.o) * ray.inv_d, Vec3::INFINITY);
        AmanatidesWoo { cur, wall, o: ray.o, inv_d: ray.inv_d, t_max, t1: ray.t1 }
    }

    /// The current cell and its exit; then the next crossing (the cursor is not done).
    #[inline]
    pub(super) fn advance(&mut self) -> Option<CellStep> {
        // A constant axis per arm keeps the walker's state in registers (an index chosen at
        // run time would send every vector through the stack).
        match argmin3(self.t_max.to_array()) {
            0 => self.advance_along::<0>(),
            1 => self.advance_along::<1>(),
            _ => self.advance_along::<2>(),
        }
    }

    #[inline(always)]
    fn advance_along<const A: usize>(&mut self) -> Option<CellStep> {
        let t = self.t_max[A];
        let out = CellStep { cell: self.cur.cell.as_uvec3(), t_exit: t.min(self.t1) };
        if t.is_nan() || t > self.t1 {
            // The segment ends inside this cell.
            self.cur.done = true;
        } else {
            self.cur.cross(A);
            self.wall[A] += self.cur.step[A] as f32;
            self.t_max[A] = (self.wall[A] - self.o[A]) * self.inv_d[A];
        }
        Some(out)
    }

    /// The same walk as the iterator, fused into one loop: `visit(cell, address, t_exit)`
    /// (address `x + res.x · (y + res.y · z)`, kept incrementally) returns true to stop, and
    /// then so does this. The state is a [`LinearWalk`], a local, so the loop runs in registers
    /// (its steps without the pausable walk's end flag); the cells, their order and their exits
    /// are the iterator's.
    #[inline]
    pub(super) fn walk_linear(self, mut visit: impl FnMut(UVec3, usize, f32) -> bool) -> bool {
        let mut w = self.linear();
        if w.done {
            return false;
        }
        loop {
            let (a, t) = w.next_axis();
            if visit(w.cell.as_uvec3(), w.addr as usize, t.min(w.t1)) {
                return true;
            }
            if w.ends_at(t) || !w.cross(a) {
                return false;
            }
        }
    }

    /// The walk as a [`LinearWalk`], which can be paused between cells.
    #[inline]
    pub fn linear(self) -> LinearWalk {
        let Cursor { cell, res, step, done } = self.cur;
        LinearWalk {
            addr: linear_index(cell.as_uvec3(), res.as_uvec3()) as isize,
            stride: [step.x as isize, (step.y * res.x) as isize, (step.z * res.x * res.y) as isize],
            cell,
            res,
            step,
            wall: self.wall,
            t_max: self.t_max,
            o: self.o,
            inv_d: self.inv_d,
            t1: self.t1,
            done,
        }
    }
}

/// Amanatides–Woo with the cell's address `x + res.x · (y + res.y · z)` kept incrementally: one
/// cell per [`LinearWalk::next_cell`], so a walk can be paused between cells (the interleaved
/// batch, [`crate::trace::interleaved`]) or run in one loop ([`AmanatidesWoo::walk_linear`]).
#[derive(Clone, Copy, Debug)]
pub struct LinearWalk {
    addr: isize,
    stride: [isize; 3],
    cell: IVec3,
    res: IVec3,
    step: IVec3,
    wall: Vec3,
    t_max: Vec3,
    o: Vec3,
    inv_d: Vec3,
    t1: f32,
    done: bool,
}

impl LinearWalk {
    /// The axis of the next crossing and its `t` (argmin3's tie rule: x before y before z).
    #[inline(always)]
    fn next_axis(&self) -> (usize, f32) {
        let (tx, ty, tz) = (self.t_max.x, self.t_max.y, self.t_max.z);
        if tx <= ty && tx <= tz {
            (0, tx)
        } else if ty <= tz {
            (1, ty)
        } else {
            (2, tz)
        }
    }

    /// Whether the segment ends in the current cell, whose exit is `t`.
    #[inline(always)]
    fn ends_at(&self, t: f32) -> bool {
        t.is_nan() || t > self.t1
    }

    /// One cell along axis `a`: false when that leaves the grid, else the axis' next wall
    /// crossing is updated. A constant axis per arm keeps the state in registers.
    #[inline(always)]
    fn cross(&mut self, a: usize) -> bool {
        self.addr += self.stride[a];
        macro_rules! cross {
            ($axis:ident) => {{
                self.cell.$axis += self.step.$axis;
                if self.cell.$axis < 0 || self.cell.$axis >= self.res.$axis {
                    return false;
                }
                self.wall.$axis += self.step.$axis as f32;
                self.t_max.$axis = (self.wall.$axis - self.o.$axis) * self.inv_d.$axis;
            }};
        }
        match a {
            0 => cross!(x),
            1 => cross!(y),
            _ => cross!(z),
        }
        true
    }

    /// The current cell, its address and the `t` where the ray leaves it (capped at the
    /// segment's end); then the walk moves on to the next cell, or ends when the segment ends in
    /// this one or the next leaves the grid. `None` once the walk has ended.
    #[inline(always)]
    pub fn next_cell(&mut self) -> Option<(UVec3, usize, f32)> {
        if self.done {
            return None;
        }
        let (a, t) = self.next_axis();
        let out = (self.cell.as_uvec3(), self.addr as usize, t.min(self.t1));
        self.done = self.ends_at(t) || !self.cross(a);
        Some(out)
    }
}
