//! Grid traversals: each one turns a clipped grid-space ray ([`GridRay`]) into the sequence of
//! cells it passes through, as an iterator of [`CellStep`]s in order of increasing `t`.
//!
//! - [`amanatides_woo`]: float 3DDDA (Amanatides & Woo 1987).
//! - [`cleary_wyvill`]: incremental crossing distances in integer fixed point and a linear cell
//!   address (Cleary & Wyvill 1988).
//! - [`liu`]: integer one-pass slice walker after Liu et al. (2004).
//! - [`bresenham`]: a naive 3-D Bresenham line, **incomplete by design**: it visits one cell per
//!   slice of the driving axis and misses cells the ray crosses (survey Figure 1). It exists to
//!   show that; closest-hit tracing with it can miss hits.
//!
//! The three exact walkers are tested to visit every cell the segment crosses (with positive
//! length), only cells it touches, in order of increasing `t`.

pub mod amanatides_woo;
pub mod bresenham;
pub mod cleary_wyvill;
pub mod liu;

use glam::{IVec3, UVec3};
use serde::{Deserialize, Serialize};

use crate::geometry::{GridRay, linear_index};

/// One visited cell and the `t` where the ray leaves it (capped at the segment end).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellStep {
    pub cell: UVec3,
    pub t_exit: f32,
}

/// The traversal algorithms (`--traversal aw|cw|liu|bresenham`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Traversal {
    #[default]
    AmanatidesWoo,
    ClearyWyvill,
    Liu,
    Bresenham,
}

impl Traversal {
    /// The exact traversals (every crossed cell is visited).
    pub const EXACT: [Traversal; 3] = [Traversal::AmanatidesWoo, Traversal::ClearyWyvill, Traversal::Liu];
    pub const ALL: [Traversal; 4] =
        [Traversal::AmanatidesWoo, Traversal::ClearyWyvill, Traversal::Liu, Traversal::Bresenham];

    pub fn short_name(self) -> &'static str {
        match self {
            Traversal::AmanatidesWoo => "aw",
            Traversal::ClearyWyvill => "cw",
            Traversal::Liu => "liu",
            Traversal::Bresenham => "bresenham",
        }
    }

    pub fn is_exact(self) -> bool {
        self != Traversal::Bresenham
    }
}

impl std::str::FromStr for Traversal {
    type Err = String;
    fn from_str(s: &str) -> Result<Traversal, String> {
        match s {
            "aw" | "amanatides-woo" => Ok(Traversal::AmanatidesWoo),
            "cw" | "cleary-wyvill" => Ok(Traversal::ClearyWyvill),
            "liu" => Ok(Traversal::Liu),
            "bresenham" => Ok(Traversal::Bresenham),
            _ => Err(format!("unknown traversal \"{s}\": expected aw, cw, liu or bresenham")),
        }
    }
}

impl std::fmt::Display for Traversal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.short_name())
    }
}

/// What a walk over blocks of cells does after a visit ([`amanatides_woo::AmanatidesWoo::walk_blocks`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Visit {
    /// The search is done.
    Stop,
    /// On to the next cell.
    Next,
    /// The cell's block is empty: on to the first cell beyond it.
    LeaveBlock,
}

/// Any walker behind one type, for callers that pick the traversal at run time and do not need
/// the last bit of speed (the closest-hit loop is generic instead).
#[derive(Clone, Debug)]
pub enum Walker {
    AmanatidesWoo(amanatides_woo::AmanatidesWoo),
    ClearyWyvill(cleary_wyvill::ClearyWyvill),
    Liu(liu::Liu),
    Bresenham(bresenham::Bresenham),
}

impl Walker {
    pub fn new(kind: Traversal, ray: &GridRay, res: UVec3) -> Walker {
        match kind {
            Traversal::AmanatidesWoo => Walker::AmanatidesWoo(amanatides_woo::AmanatidesWoo::new(ray, res)),
            Traversal::ClearyWyvill => Walker::ClearyWyvill(cleary_wyvill::ClearyWyvill::new(ray, res)),
            Traversal::Liu => Walker::Liu(liu::Liu::new(ray, res)),
            Traversal::Bresenham => Walker::Bresenham(bresenham::Bresenham::new(ray, res)),
        }
    }
}

impl Iterator for Walker {
    type Item = CellStep;
    fn next(&mut self) -> Option<CellStep> {
        match self {
            Walker::AmanatidesWoo(w) => w.next(),
            Walker::ClearyWyvill(w) => w.next(),
            Walker::Liu(w) => w.next(),
            Walker::Bresenham(w) => w.next(),
        }
    }
}

/// Walks the cells `ray` crosses in a grid of `res`, in order, with the traversal `kind`:
/// `visit(cell, address, t_exit)` (address `x + res.x · (y + res.y · z)`) returns true to stop,
/// and then so does `walk`. Every structure's loop goes through here with its cell test
/// injected; Amanatides–Woo (the default) runs as one fused loop, the others through their
/// iterators, each compiled into the caller.
#[inline]
pub fn walk(kind: Traversal, ray: &GridRay, res: UVec3, mut visit: impl FnMut(UVec3, usize, f32) -> bool) -> bool {
    #[inline]
    fn each(
        steps: impl Iterator<Item = CellStep>,
        res: UVec3,
        visit: &mut impl FnMut(UVec3, usize, f32) -> bool,
    ) -> bool {
        steps.into_iter().any(|s| visit(s.cell, linear_index(s.cell, res), s.t_exit))
    }
    match kind {
        Traversal::AmanatidesWoo => amanatides_woo::AmanatidesWoo::new(ray, res).walk_linear(visit),
        Traversal::ClearyWyvill => each(cleary_wyvill::ClearyWyvill::new(ray, res), res, &mut visit),
        Traversal::Liu => each(liu::Liu::new(ray, res), res, &mut visit),
        Traversal::Bresenham => each(bresenham::Bresenham::new(ray, res), res, &mut visit),
    }
}

/// [`walk`], also counting the cells visited (for the rays' stats): `(stopped, cells)`. The
/// count is a local of the walk's loop and stays in a register; counted in the search instead
/// (behind the `&mut` every visit takes) it went through memory at every cell.
#[inline]
pub fn walk_counted(
    kind: Traversal,
    ray: &GridRay,
    res: UVec3,
    mut visit: impl FnMut(UVec3, usize, f32) -> bool,
) -> (bool, u32) {
    let mut cells = 0;
    let stopped = walk(kind, ray, res, |cell, addr, t_exit| {
        cells += 1;
        visit(cell, addr, t_exit)
    });
    (stopped, cells)
}

/// What the exact walkers share: the cell they are in, the grid's resolution, the step
/// direction per axis and whether the walk has ended. WGSL: `Cursor` in
/// shaders/shared/walker_common.wgsl.
#[derive(Clone, Copy, Debug)]
pub struct Cursor {
    pub cell: IVec3,
    pub res: IVec3,
    pub step: IVec3,
    pub done: bool,
}

impl Cursor {
    /// In the segment's first cell, stepping along the sign of the direction on each axis
    /// (0 where the ray does not move).
    pub fn start(ray: &GridRay, res: UVec3) -> Cursor {
        let step = IVec3::from_array(std::array::from_fn(|a| sign_step(ray.d[a])));
        Cursor { cell: ray.start_cell(res).as_ivec3(), res: res.as_ivec3(), step, done: false }
    }

    /// The wall the walk crosses next on axis `a` (as f32: exact for any resolution ≤ 2^24).
    #[inline]
    pub fn wall(&self, a: usize) -> f32 {
        (self.cell[a] + (self.step[a] > 0) as i32) as f32
    }

    /// One cell along axis `a`; the walk ends when that leaves the grid.
    #[inline]
    pub fn cross(&mut self, a: usize) {
        self.cell[a] += self.step[a];
        if self.cell[a] < 0 || self.cell[a] >= self.res[a] {
            self.done = true;
        }
    }
}

/// -1, 0 or 1 (0 for ±0 and NaN).
fn sign_step(x: f32) -> i32 {
    (x > 0.0) as i32 - (x < 0.0) as i32
}

/// The exact walkers' `Iterator`: nothing once the cursor is done, else the walker's `advance`.
macro_rules! cell_iterator {
    ($($walker:ty),*) => {$(
        impl Iterator for $walker {
            type Item = CellStep;
            #[inline]
            fn next(&mut self) -> Option<CellStep> {
                if self.cur.done { None } else { self.advance() }
            }
        }
    )*};
}
cell_iterator!(amanatides_woo::AmanatidesWoo, cleary_wyvill::ClearyWyvill, liu::Liu);

/// The axis of the smallest of three values; ties go to the lower axis (x before y before z).
/// The tie-break every walker shares with its WGSL port (`argmin3_of`).
#[inline]
pub(crate) fn argmin3<T: PartialOrd>(v: [T; 3]) -> usize {
    if v[0] <= v[1] && v[0] <= v[2] {
        0
    } else if v[1] <= v[2] {
        1
    } else {
        2
    }
}
