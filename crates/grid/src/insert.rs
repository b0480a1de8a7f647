//! Which cells a triangle goes into (sort-last insertion, survey §3): by its bounding box
//! (fast, more references) or by an exact triangle–box overlap test (separating axes,
//! Akenine-Möller 2001). Both are conservative: every cell within
//! [`INSERT_MARGIN_CELLS`](crate::geometry::INSERT_MARGIN_CELLS) of the triangle is included,
//! and the exact test runs in f64 against the enlarged cell.
//!
//! Zero-area triangles are inserted like any other: three collinear points can round to a
//! sliver of non-zero area in the f32 shear of the watertight test, and the brute-force
//! reference would then hit them, so skipping them would break bit-exact agreement.

use glam::{DVec3, UVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::geometry::GridGeometry;

/// How triangles are assigned to cells.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum InsertMode {
    /// Every cell overlapped by the triangle's bounding box.
    #[default]
    BoundingBox,
    /// Only cells the triangle itself overlaps (SAT test per candidate cell).
    Exact,
}

impl InsertMode {
    /// Every insertion mode.
    pub const ALL: [InsertMode; 2] = [InsertMode::BoundingBox, InsertMode::Exact];
}

/// A triangle in grid space (cells are unit cubes), f64.
#[derive(Clone, Copy, Debug)]
pub struct GridTriangle {
    pub v: [DVec3; 3],
    pub lo: UVec3,
    pub hi: UVec3,
    /// Insertion margin in cells (also applied by the exact test).
    pub margin: f64,
}

/// The triangle in grid space with its conservative cell range: every cell within `margin`
/// cells of the triangle (see [`crate::geometry::INSERT_MARGIN_CELLS`]). The range is clamped to the grid (triangles outside the grid box are clamped
/// too; a grid is always built over bounds that contain all triangles).
#[inline]
pub fn prepare(geom: &GridGeometry, tri: &[Vec3; 3], margin: f64) -> GridTriangle {
    let min = geom.min.as_dvec3();
    let inv = geom.inv_cell.as_dvec3();
    let v = tri.map(|p| (p.as_dvec3() - min) * inv);
    let [lo, hi] = box_cell_range(geom, tri, margin as f32);
    GridTriangle { v, lo, hi, margin }
}

/// The cells within `margin` cells of a triangle's bounding box, clamped to the grid: computed in
/// f32 with operations every WGSL implementation rounds the same way (a subtraction, then a
/// product, then exact floor and fraction), so that the GPU build
/// (`shaders/build_count.wgsl`, `cell_range`) finds exactly the same cells. The rounding (at most
/// about 2^-24 × 2 × 1024 cells) is far below the margin, so the range stays conservative.
#[inline]
pub fn box_cell_range(geom: &GridGeometry, tri: &[Vec3; 3], margin: f32) -> [UVec3; 2] {
    let g = tri.map(|p| (p - geom.min) * geom.inv_cell);
    grid_box_cells(g[0].min(g[1]).min(g[2]), g[0].max(g[1]).max(g[2]), geom.res, margin)
}

/// The cells within `margin` of the grid-space box `[lo, hi]`, clamped to `res`: on each axis
/// the cell of `x − margin` and the cell of `x + margin`, from `x`'s floor and exact fraction.
#[inline]
pub fn grid_box_cells(lo: Vec3, hi: Vec3, res: UVec3, margin: f32) -> [UVec3; 2] {
    let cell = |x: f32, n: u32, upper: bool| -> u32 {
        // Clamped to [0, n] first, so truncation is floor and the fraction is exact.
        let c = x.clamp(0.0, n as f32);
        let i = c as u32;
        let frac = c - i as f32;
        let i = if upper { i + (frac >= 1.0 - margin) as u32 } else { i - (frac < margin && i > 0) as u32 };
        i.min(n - 1)
    };
    [
        UVec3::new(cell(lo.x, res.x, false), cell(lo.y, res.y, false), cell(lo.z, res.z, false)),
        UVec3::new(cell(hi.x, res.x, true), cell(hi.y, res.y, true), cell(hi.z, res.z, true)),
    ]
}

/// Calls `f(cell_index)` for every cell `tri` is inserted into, in increasing index order
/// (z, then y, then x), and returns how many.
#[inline]
pub fn for_each_cell(geom: &GridGeometry, g: &GridTriangle, mode: InsertMode, f: impl FnMut(usize)) -> u32 {
    for_each_cell_in_layers(geom, g, mode, 0..geom.res.z, f)
}

/// [`for_each_cell`] restricted to the z layers `layers` (the parallel build gives each thread
/// a slab of layers). The result over all slabs is exactly [`for_each_cell`]'s: in particular
/// a triangle's single-cell shortcut is decided on its whole range, not on the slab's part.
#[inline]
pub fn for_each_cell_in_layers(
    geom: &GridGeometry,
    g: &GridTriangle,
    mode: InsertMode,
    layers: std::ops::Range<u32>,
    mut f: impl FnMut(usize),
) -> u32 {
    if mode == InsertMode::BoundingBox {
        return for_each_box_cell_in_layers(geom, [g.lo, g.hi], layers, f);
    }
    let single = g.lo == g.hi;
    let mut n = 0;
    for z in g.lo.z.max(layers.start)..=g.hi.z.min(layers.end.saturating_sub(1)) {
        for y in g.lo.y..=g.hi.y {
            for x in g.lo.x..=g.hi.x {
                let c = UVec3::new(x, y, z);
                if !single && !tri_box_overlap(&g.v, c.as_dvec3() + DVec3::splat(0.5), 0.5 + g.margin) {
                    continue;
                }
                f(geom.cell_index(c));
                n += 1;
            }
        }
    }
    n
}

/// Bounding-box insertion of the cell range `[lo, hi]` (a [`prepare`]d triangle's), in the
/// z layers `layers`: `f(cell_index)` in increasing order; returns how many.
#[inline]
pub fn for_each_box_cell_in_layers(
    geom: &GridGeometry,
    [lo, hi]: [UVec3; 2],
    layers: std::ops::Range<u32>,
    mut f: impl FnMut(usize),
) -> u32 {
    let mut n = 0;
    for z in lo.z.max(layers.start)..=hi.z.min(layers.end.saturating_sub(1)) {
        for y in lo.y..=hi.y {
            let row = geom.cell_index(UVec3::new(lo.x, y, z));
            for c in row..=row + (hi.x - lo.x) as usize {
                f(c);
            }
            n += hi.x - lo.x + 1;
        }
    }
    n
}

/// Number of cells `tri` goes into (for counting N_m without building).
#[inline]
pub fn cell_count(geom: &GridGeometry, g: &GridTriangle, mode: InsertMode) -> u64 {
    match mode {
        InsertMode::BoundingBox => {
            let e = g.hi - g.lo + UVec3::ONE;
            e.x as u64 * e.y as u64 * e.z as u64
        }
        InsertMode::Exact => for_each_cell(geom, g, mode, |_| {}) as u64,
    }
}

/// Separating-axis triangle/box overlap test (Akenine-Möller), box = cube at `c` with half
/// size `h`. Touching counts as overlap.
pub fn tri_box_overlap(tri: &[DVec3; 3], c: DVec3, h: f64) -> bool {
    let v0 = tri[0] - c;
    let v1 = tri[1] - c;
    let v2 = tri[2] - c;
    let e = [v1 - v0, v2 - v1, v0 - v2];
    // 9 axes: box axis × triangle edge.
    for edge in e {
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            let a = axis.cross(edge);
            if a == DVec3::ZERO {
                continue;
            }
            let p0 = a.dot(v0);
            let p1 = a.dot(v1);
            let p2 = a.dot(v2);
            let r = h * (a.x.abs() + a.y.abs() + a.z.abs());
            if p0.min(p1).min(p2) > r || p0.max(p1).max(p2) < -r {
                return false;
            }
        }
    }
    // Box face normals: the triangle's bounding box against the box.
    let mn = v0.min(v1).min(v2);
    let mx = v0.max(v1).max(v2);
    if mn.x > h || mn.y > h || mn.z > h || mx.x < -h || mx.y < -h || mx.z < -h {
        return false;
    }
    // Triangle plane.
    let n = e[0].cross(e[1]);
    let d = n.dot(v0);
    let r = h * (n.x.abs() + n.y.abs() + n.z.abs());
    d.abs() <= r
}
