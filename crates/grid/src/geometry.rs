//! Where a grid sits in space and how a ray enters it: the grid box, per-axis resolution, and
//! the ray in grid space (cells are unit cubes there, and `t` is unchanged).
//!
//! Robustness (Lagae & Dutré's "conservative insertion"): the traversals compute cell
//! boundaries in f32 (fixed point for Cleary–Wyvill and Liu), so the `t` where they say a ray
//! leaves a cell can be off by a tiny fraction of a cell. Every structure therefore inserts a
//! triangle into all cells within [`INSERT_MARGIN_CELLS`] of it, which is far larger than
//! those errors (≤ ~5e-4 cells at the largest resolution, see each traversal's doc): a hit
//! whose `t` a traversal attributes to the "wrong" side of a boundary is still found in a cell
//! already visited. The grid box is padded too, so no triangle touches its faces.

use glam::{UVec3, Vec3, Vec3A};
use gridrt_scene::Aabb;
use serde::{Deserialize, Serialize};

use crate::ray::PreparedRay;

/// Largest resolution along one axis. Liu's fixed-point walker keeps coordinates in i32 with
/// 20 fractional bits: 1024 · 2^20 = 2^30 leaves headroom.
pub const MAX_AXIS_RES: u32 = 1024;
/// Insertion margin, in cells, on every side of a triangle (see the module doc).
pub const INSERT_MARGIN_CELLS: f64 = 1.0 / 256.0;

/// The box and resolution of a uniform grid.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridGeometry {
    pub min: Vec3,
    pub max: Vec3,
    pub res: UVec3,
    /// Cell size per axis (world units).
    pub cell: Vec3,
    /// 1 / cell size per axis.
    pub inv_cell: Vec3,
}

/// The least extent of a grid box on any axis (2^-100, about 8e-31): its cells' reciprocal sizes
/// stay far within f32 at [`MAX_AXIS_RES`] cells.
pub const MIN_BOX_EXTENT: f32 = 7.888609e-31;

/// The padded box a grid over `bounds` uses: every axis gets a non-zero extent and a margin.
pub fn padded_bounds(bounds: &Aabb) -> Aabb {
    if bounds.is_empty() {
        return Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
    }
    let ext = bounds.extent();
    let big = ext.max_element();
    // Flat axes (all z equal, a single triangle in a plane) still need a slab of cells. Both
    // sizes are relative to the scene (its extent, and its distance from the origin, which
    // bounds how finely f32 places its corners), so a scene nanometres across gets the cells of
    // the same scene in metres; only a scene of one point at the origin takes the least box
    // (and a pad of 1e-5 of it, the pad's share of the extent).
    let scale = bounds.min.abs().max(bounds.max.abs()).max_element();
    let floor = (big * 1e-3).max(scale * 1e-5).max(MIN_BOX_EXTENT);
    let pad = Vec3::splat((big * 1e-5).max(scale * 4e-7).max(MIN_BOX_EXTENT * 1e-5));
    let mut min = bounds.min - pad;
    let mut max = bounds.max + pad;
    for a in 0..3 {
        if max[a] - min[a] < floor {
            let c = 0.5 * (min[a] + max[a]);
            min[a] = c - floor * 0.5;
            max[a] = c + floor * 0.5;
        }
    }
    Aabb { min, max }
}

/// The linear index of cell `c` in a grid of `res` cells: x fastest, then y, then z. The one
/// cell order of every grid, walk and GPU layout.
#[inline]
pub fn linear_index(c: UVec3, res: UVec3) -> usize {
    (c.x + res.x * (c.y + res.y * c.z)) as usize
}

impl GridGeometry {
    /// A grid over `bounds` (padded, see [`padded_bounds`]) with resolution `res`, each axis
    /// clamped to `1..=MAX_AXIS_RES`.
    pub fn new(bounds: &Aabb, res: [u32; 3]) -> GridGeometry {
        let b = padded_bounds(bounds);
        let res = UVec3::from_array(res).clamp(UVec3::ONE, UVec3::splat(MAX_AXIS_RES));
        let cell = (b.max - b.min) / res.as_vec3();
        GridGeometry { min: b.min, max: b.max, res, cell, inv_cell: Vec3::ONE / cell }
    }

    pub fn cell_count(&self) -> u64 {
        self.res.x as u64 * self.res.y as u64 * self.res.z as u64
    }

    /// Linear cell index, x fastest.
    #[inline]
    pub fn cell_index(&self, c: UVec3) -> usize {
        linear_index(c, self.res)
    }

    /// The ray in grid space clipped to the grid box and to `[tmin, tmax]`, or `None` when the
    /// segment misses the grid; its `t` in the walk's units ([`PreparedRay::walk_t`]).
    #[inline]
    pub fn clip(&self, r: &PreparedRay) -> Option<GridRay> {
        let (tmin, tmax) = if r.t_scale > 1.0 { widened(r) } else { (r.tmin, r.tmax) };
        self.clip_unscaled(r, tmin, tmax)
    }

    /// [`GridGeometry::clip`] of the segment `[tmin, tmax]` (ray units) as given: for rays whose
    /// walk is not scaled (`t_scale` 1, which the packets take; they trace a scaled ray alone).
    #[inline]
    pub fn clip_unscaled(&self, r: &PreparedRay, tmin: f32, tmax: f32) -> Option<GridRay> {
        let (tmin, tmax) = (r.walk_t(tmin), r.walk_t(tmax));
        GridRay::clipped((r.org - self.min) * self.inv_cell, r.walk_dir() * self.inv_cell, self.res, tmin, tmax)
    }
}

/// A scaled walk's segment (a large direction), widened by an ulp of the ray's `t` on each
/// side: a hit whose exact `t` lies just outside [tmin, tmax] rounds into it, and across a tiny
/// scene all of its hits' `t` may underflow to zero. An unscaled walk is not widened: there an
/// ulp is less than the insertion margin (directions below 2^16 over cells of at least 2^-110:
/// under 2^-23 of a cell at zero), and widening would put subnormal values, slow on x86, into
/// every walk. Out of line: few rays take it.
#[cold]
#[inline(never)]
fn widened(r: &PreparedRay) -> (f32, f32) {
    (r.tmin.next_down(), r.tmax.next_up())
}

/// A ray in grid space (cell `(i, j, k)` is the unit cube at `(i, j, k)`), clipped: the
/// segment `[t0, t1]` lies in the grid box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridRay {
    pub o: Vec3,
    pub d: Vec3,
    pub inv_d: Vec3,
    pub t0: f32,
    pub t1: f32,
}

impl GridRay {
    /// The ray `o + t·d` (already in grid space) clipped to the box `[0, res]` and to
    /// `[tmin, tmax]`; `None` when nothing is left. Shared by every level of every structure,
    /// so that all of them treat parallel components and empty ranges alike.
    #[inline]
    pub fn clipped(o: Vec3, d: Vec3, res: UVec3, tmin: f32, tmax: f32) -> Option<GridRay> {
        // On SIMD lanes (one division for the three reciprocals); each lane's operations and
        // the order of the comparisons are the scalar rule's. A component so small that its
        // reciprocal overflows is treated as exactly parallel, by the clip and by every walker
        // (they test `d[a] == 0`).
        let (o4, mut d4) = (Vec3A::from(o), Vec3A::from(d));
        let mut inv4 = Vec3A::ONE / d4;
        let parallel = !inv4.is_finite_mask();
        let res = Vec3A::from(res.as_vec3());
        if parallel.any() {
            d4 = Vec3A::select(parallel, Vec3A::ZERO, d4);
            inv4 = Vec3A::select(parallel, Vec3A::INFINITY, inv4);
            let inside = o4.cmpge(Vec3A::ZERO) & o4.cmple(res);
            if (parallel & !inside).any() {
                return None;
            }
        }
        let ta = (Vec3A::ZERO - o4) * inv4;
        let tb = (res - o4) * inv4;
        let ordered = ta.cmple(tb);
        let (lo, hi) = (Vec3A::select(ordered, ta, tb), Vec3A::select(ordered, tb, ta));
        // An axis the ray is parallel to bounds nothing (its slab test above is done).
        let lo = Vec3A::select(parallel, Vec3A::NEG_INFINITY, lo);
        let hi = Vec3A::select(parallel, Vec3A::INFINITY, hi);
        // Axis by axis, a bound replaces t0 (t1) only when strictly inside: selects, not
        // branches (a random ray's order of slab crossings is unpredictable).
        let mut t0 = tmin;
        let mut t1 = tmax;
        for a in 0..3 {
            t0 = if lo[a] > t0 { lo[a] } else { t0 };
            t1 = if hi[a] < t1 { hi[a] } else { t1 };
        }
        if !t0.is_finite() || !t1.is_finite() || t0 > t1 {
            return None;
        }
        let (d, inv_d) = (Vec3::from(d4), Vec3::from(inv4));
        Some(GridRay { o, d, inv_d, t0, t1 })
    }

    /// This ray seen from a sub-grid of `sub_res` cells filling cell `c` (a hierarchy's child
    /// grid), over the parent's `[t0, t1]` for that cell.
    ///
    /// Deliberately not clipped to the child's box: the parent walker may place the ray in a
    /// cell it only grazes (within the insertion margin; Liu's fixed point does this on walls),
    /// and an exact clip would then drop the cell and the hits inserted there. The child walker
    /// clamps its cells into the sub-grid instead.
    #[inline]
    pub fn child(&self, c: UVec3, sub_res: UVec3, t0: f32, t1: f32) -> GridRay {
        let s = Vec3A::from(sub_res.as_vec3());
        let d = Vec3A::from(self.d) * s;
        // A component whose reciprocal overflows (or is NaN) moves the ray along nothing: it
        // becomes 0, and its reciprocal 1 / +0 = +inf. One vector division, no branches.
        let inv = Vec3A::ONE / d;
        let parallel = !inv.is_finite_mask();
        let (d, inv_d) = (Vec3A::select(parallel, Vec3A::ZERO, d), Vec3A::select(parallel, Vec3A::INFINITY, inv));
        let o = (Vec3A::from(self.o) - Vec3A::from(c.as_vec3())) * s;
        GridRay { o: o.into(), d: d.into(), inv_d: inv_d.into(), t0, t1 }
    }

    /// The cell containing the segment's start, clamped into the grid.
    #[inline]
    pub fn start_cell(&self, res: UVec3) -> UVec3 {
        let p = self.o + self.d * self.t0;
        cell_of(p, res)
    }

    /// The cell containing the segment's end, clamped into the grid.
    #[inline]
    pub fn end_cell(&self, res: UVec3) -> UVec3 {
        let p = self.o + self.d * self.t1;
        cell_of(p, res)
    }

    /// Where the ray leaves cell `c` (the nearest far-side plane crossing), capped at `t1`.
    /// Computed from the cell index, so walkers that do not track `t` (Liu, Bresenham) report
    /// the same geometric exit as the float walkers.
    #[inline]
    pub fn exit_of_cell(&self, c: UVec3) -> f32 {
        let mut t = self.t1;
        for a in 0..3 {
            if self.d[a] != 0.0 {
                let plane = if self.d[a] > 0.0 { c[a] as f32 + 1.0 } else { c[a] as f32 };
                let ta = (plane - self.o[a]) * self.inv_d[a];
                if ta < t {
                    t = ta;
                }
            }
        }
        t
    }
}

#[inline]
fn cell_of(p: Vec3, res: UVec3) -> UVec3 {
    let max = (res - UVec3::ONE).as_vec3();
    // floor(p) clamped to [0, res − 1], without the libm call `floor` is on baseline x86-64:
    // inside [0, res − 1] truncation is the floor, and below 0 (or above res − 1) both give the
    // bound. NaN-free by construction (p is finite); the clamp also handles the far faces.
    p.clamp(Vec3::ZERO, max).as_uvec3()
}
