//! Amanatides & Woo (1987) 3DDDA in floating point.
//!
//! Per axis: `t_max` (the `t` of the next wall crossing); each step moves along the axis with
//! the smallest `t_max` and advances that axis' crossing. The survey's incremental update
//! `t_max += t_delta` accumulates one rounding per step (up to ~0.01 cell after a thousand steps
//! from a distant origin), so this implementation evaluates the same quantity from the integer
//! wall index, `t_max = (wall − o) · (1/d)`: no drift, same comparisons, and a form no shader
//! compiler can contract into an FMA, so the WGSL port takes exactly the same steps.

use glam::{IVec3, UVec3, Vec3};
use wide::f32x8;

use super::{CellStep, Cursor, Visit, argmin3};
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
    #[inline(always)]
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

    /// [`AmanatidesWoo::walk_linear`] over a grid in blocks of 2^`log2` cells per edge (a
    /// macrocell grid's fine cells): `visit(cell, address, t_exit)` says whether to stop, go on
    /// to the next cell, or leave the cell's block, which holds nothing; then the walk crosses
    /// blocks while `empty_block(block)` ([`LinearWalk::cross_blocks`]). The cells visited are
    /// the flat walk's, less those in empty blocks. Returns whether `visit` stopped the walk,
    /// and the number of visits and empty blocks crossed.
    #[inline]
    pub fn walk_blocks(
        self,
        log2: u32,
        empty_block: impl Fn(UVec3) -> bool,
        mut visit: impl FnMut(UVec3, usize, f32) -> Visit,
    ) -> (bool, u32) {
        let mut w = self.linear();
        let mut visits = 0;
        if w.done {
            return (false, visits);
        }
        loop {
            let (a, t) = w.next_axis();
            visits += 1;
            match visit(w.cell.as_uvec3(), w.addr as usize, t.min(w.t1)) {
                Visit::Stop => return (true, visits),
                Visit::Next if w.ends_at(t) || !w.cross(a) => return (false, visits),
                Visit::Next => {}
                Visit::LeaveBlock if !w.cross_blocks(log2, &empty_block, &mut visits) => return (false, visits),
                Visit::LeaveBlock => {}
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

    /// From the current cell, whose block of 2^`log2` cells per edge is empty (blocks are
    /// aligned to multiples of the edge and tile the grid; the last on an axis may be cut short
    /// by the grid's end, its far wall then the grid's): walks the grid of blocks to the
    /// first one that `empty_block(block)` says is not, and sets this walk at the cell, walls
    /// and crossings the cell-by-cell walk reaches there; each empty block entered after the
    /// current one adds 1 to `crossed`. False when the walk ends first (the segment ends, or the
    /// grid does).
    ///
    /// Exact, not estimated from an entry point: a block's walls are walls of this grid and
    /// their crossings are computed as a step computes them, `(wall − o) · (1/d)`; the steps
    /// take walls in the order of `(t, axis)` (each axis' crossings do not decrease along its
    /// walls, ties go to the lower axis), so the walk of blocks crosses the block walls in the
    /// cell walk's order, and on entering a block through axis `out` at `t`, the cell walk has
    /// crossed on each other axis exactly the walls whose `(t, axis)` is less (counted on SIMD
    /// lanes among the block's walls on that axis). The hierarchical DDA of the survey's
    /// macrocells without a restarted walk's rounding: the cells visited after the blocks, their
    /// order and their exits are the flat walk's.
    #[inline]
    pub fn cross_blocks(&mut self, log2: u32, empty_block: impl Fn(UVec3) -> bool, crossed: &mut u32) -> bool {
        let res = (self.res + IVec3::splat((1 << log2) - 1)) >> log2;
        let mut block = self.cell >> log2;
        let [(wx, tx), (wy, ty), (wz, tz)] =
            [self.block_exit::<0>(log2), self.block_exit::<1>(log2), self.block_exit::<2>(log2)];
        let (mut wall, mut t_max) = (IVec3::new(wx, wy, wz), Vec3::new(tx, ty, tz));
        // A constant axis per arm keeps the blocks' walk in registers, as the cells' walk.
        macro_rules! cross {
            ($axis:ident) => {{
                block.$axis += self.step.$axis;
                if block.$axis < 0 || block.$axis >= res.$axis {
                    self.done = true;
                    return false;
                }
                wall.$axis = (wall.$axis + (self.step.$axis << log2)).min(self.res.$axis);
                t_max.$axis = (wall.$axis as f32 - self.o.$axis) * self.inv_d.$axis;
            }};
        }
        loop {
            let out = argmin3(t_max.to_array());
            let t = match out {
                0 => t_max.x,
                1 => t_max.y,
                _ => t_max.z,
            };
            if t.is_nan() || t > self.t1 {
                self.done = true;
                return false;
            }
            match out {
                0 => cross!(x),
                1 => cross!(y),
                _ => cross!(z),
            }
            if !empty_block(block.as_uvec3()) {
                self.enter_block::<0>(log2, block.x, out, t);
                self.enter_block::<1>(log2, block.y, out, t);
                self.enter_block::<2>(log2, block.z, out, t);
                self.addr = linear_index(self.cell.as_uvec3(), self.res.as_uvec3()) as isize;
                return true;
            }
            *crossed += 1;
        }
    }

    /// Axis `A`'s first wall beyond the current cell's block of 2^`log2` cells per edge (at
    /// most the grid's end), and its crossing (never, on an axis the ray does not move along).
    #[inline(always)]
    fn block_exit<const A: usize>(&self, log2: u32) -> (i32, f32) {
        let step = self.step[A];
        if step == 0 {
            return (0, f32::INFINITY);
        }
        let lo = (self.cell[A] >> log2) << log2;
        let wall = if step > 0 { (lo + (1 << log2)).min(self.res[A]) } else { lo };
        (wall, (wall as f32 - self.o[A]) * self.inv_d[A])
    }

    /// Axis `A`'s part of [`LinearWalk::cross_blocks`]: the cell, next wall and crossing on
    /// entering block `b` (its index on this axis) at `t` through axis `out`. On `out`, the
    /// block's first cell. On another axis, the walls whose `(t, axis)` is less are crossed
    /// (a prefix of the walls in the step's order), counted from the walk's next wall when the
    /// walk is still in block `b` on this axis (the walls behind its first cell count as
    /// crossed even where their `t` ties with the start: the first cell is where the segment
    /// starts), else from the block's first wall (all walls before it have been crossed).
    #[inline(always)]
    fn enter_block<const A: usize>(&mut self, log2: u32, b: i32, out: usize, t: f32) {
        let step = self.step[A];
        if step == 0 {
            return;
        }
        // Moving down, a block is entered from above, so never the grid's last, cut-short one;
        // the bound keeps the first cell in the grid regardless.
        let first = if step > 0 { b << log2 } else { ((b << log2) + (1 << log2) - 1).min(self.res[A] - 1) };
        let (mut cell, mut wall) = (first, first + (step > 0) as i32);
        if A != out {
            if self.cell[A] >> log2 == b {
                cell = self.cell[A];
                wall = self.wall[A] as i32;
            }
            let (o, inv_d) = (f32x8::splat(self.o[A]), f32x8::splat(self.inv_d[A]));
            let (tv, lanes) = (f32x8::splat(t), f32x8::from([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]));
            let stepv = f32x8::splat(step as f32);
            // Eight walls at a time (an edge of 16 cells may take two rounds); a wall's crossing
            // is the step's own arithmetic (integral walls are exact in f32).
            loop {
                let t_walls = ((f32x8::splat(wall as f32) + lanes * stepv) - o) * inv_d;
                let tie = if A < out { t_walls.simd_eq(tv) } else { f32x8::ZERO };
                let n = (!(t_walls.simd_lt(tv) | tie).to_bitmask()).trailing_zeros() as i32;
                cell += n * step;
                wall += n * step;
                if n < 8 {
                    break;
                }
            }
        }
        self.cell[A] = cell;
        let wall = wall as f32;
        self.wall[A] = wall;
        self.t_max[A] = (wall - self.o[A]) * self.inv_d[A];
    }

    /// The current cell and its address, without moving on; `None` once the walk has ended.
    #[inline(always)]
    pub fn current(&self) -> Option<(UVec3, usize)> {
        (!self.done).then(|| (self.cell.as_uvec3(), self.addr as usize))
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
