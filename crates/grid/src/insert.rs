//! Which cells a triangle goes into (sort-last insertion, survey §3): by its bounding box
//! (fast, more references) or by an exact triangle–box overlap test (separating axes,
//! Akenine-Möller 2001). Both are conservative: every cell within
//! [`INSERT_MARGIN_CELLS`](crate::geometry::INSERT_MARGIN_CELLS) of the triangle is included,
//! and the exact test runs in f64 against the enlarged cell.
//!
//! The cells of one row (fixed y and z) that a triangle overlaps are a run: the distance from a
//! cell's center to the (convex) triangle is a convex function along the row, so the centers
//! within the enlarged half size form an interval. Exact insertion therefore tests each row
//! inward from both ends and takes the cells between its first and last overlap untested.
//!
//! Zero-area triangles are inserted like any other: three collinear points can round to a
//! sliver of non-zero area in the f32 shear of the watertight test, and the brute-force
//! reference would then hit them, so skipping them would break bit-exact agreement.

use glam::{DVec3, UVec3, Vec3, Vec3A};
use serde::{Deserialize, Serialize};
use wide::{f32x4, i32x4};

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
    // Vec3A: the same IEEE operations per lane as Vec3, four lanes at a time.
    let (min, inv) = (Vec3A::from(geom.min), Vec3A::from(geom.inv_cell));
    let g = tri.map(|p| (Vec3A::from(p) - min) * inv);
    grid_box_cells_a(g[0].min(g[1]).min(g[2]), g[0].max(g[1]).max(g[2]), geom.res, margin)
}

/// The cells within `margin` of the grid-space box `[lo, hi]`, clamped to `res`: on each axis
/// the cell of `x − margin` and the cell of `x + margin`, from `x`'s floor and exact fraction.
#[inline]
pub fn grid_box_cells(lo: Vec3, hi: Vec3, res: UVec3, margin: f32) -> [UVec3; 2] {
    grid_box_cells_a(lo.into(), hi.into(), res, margin)
}

/// [`grid_box_cells`] one axis at a time: the rule as the GPU build writes it, which the vector
/// version below (every CPU build's) must equal bit for bit (a unit test compares them).
#[cfg(test)]
fn grid_box_cells_scalar(lo: Vec3A, hi: Vec3A, res: UVec3, margin: f32) -> [UVec3; 2] {
    let cell = |x: f32, n: u32, upper: bool| -> u32 {
        // Clamped to [0, n] first (NaN to 0), so truncation is floor and the fraction is exact.
        let c = x.max(0.0).min(n as f32);
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

/// [`grid_box_cells_scalar`] on the three axes at once (four lanes: SSE2 on x86-64): the
/// binning and the guess-and-check compute a range per triangle, and the scalar rule's
/// conversions and selects were a fifth of a flat build.
#[inline]
fn grid_box_cells_a(lo: Vec3A, hi: Vec3A, res: UVec3, margin: f32) -> [UVec3; 2] {
    let n = i32x4::new([res.x as i32, res.y as i32, res.z as i32, 1]);
    let lanes = |v: Vec3A| f32x4::new(v.extend(0.0).to_array());
    let corner = |v: i32x4| {
        let a = v.to_array();
        UVec3::new(a[0] as u32, a[1] as u32, a[2] as u32)
    };
    [corner(cell_lanes(lanes(lo), n, false, margin)), corner(cell_lanes(lanes(hi), n, true, margin))]
}

/// The rule of [`grid_box_cells_scalar`] on four lanes, each a grid-space coordinate `x` on an
/// axis of `n` cells: the lower (`upper` false) or upper cell within `margin`. The lanes are a
/// grid's axes in [`grid_box_cells`], one axis of four grids in guess-and-check's counts.
#[inline(always)]
pub(crate) fn cell_lanes(x: f32x4, n: i32x4, upper: bool, margin: f32) -> i32x4 {
    // max(x, 0) gives 0 for NaN (its second operand), as f32::max does; then the values are in
    // [0, n], where truncation is floor and the fraction is exact.
    let c = x.fast_max(f32x4::ZERO).fast_min(n.round_float());
    let i = c.fast_trunc_int();
    let frac = c - i.round_float();
    // A true comparison is all ones (−1): adding it steps one cell down, subtracting one up.
    let mask = |m: f32x4| bytemuck::cast::<f32x4, i32x4>(m);
    let i = if upper {
        i - mask(frac.simd_ge(f32x4::splat(1.0 - margin)))
    } else {
        i + (mask(frac.simd_lt(f32x4::splat(margin))) & i.simd_gt(i32x4::ZERO))
    };
    i.min(n - i32x4::splat(1))
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
    for_each_run_in_layers(geom, g, mode, layers, |run| run.for_each(&mut f))
}

/// [`for_each_cell_in_layers`] a row at a time: `f(cells)` for each run of consecutive cell
/// indices (part of one x row), in increasing order; returns how many cells.
#[inline]
pub fn for_each_run_in_layers(
    geom: &GridGeometry,
    g: &GridTriangle,
    mode: InsertMode,
    layers: std::ops::Range<u32>,
    mut f: impl FnMut(std::ops::Range<usize>),
) -> u32 {
    if mode == InsertMode::BoundingBox {
        return for_each_box_run_in_layers(geom, [g.lo, g.hi], layers, f);
    }
    let mut n = 0;
    let z_range = g.lo.z.max(layers.start)..=g.hi.z.min(layers.end.saturating_sub(1));
    if g.lo == g.hi {
        for z in z_range {
            let c = geom.cell_index(UVec3::new(g.lo.x, g.lo.y, z));
            f(c..c + 1);
            n += 1;
        }
        return n;
    }
    let test = OverlapTest::new(&g.v, 0.5 + g.margin);
    let overlaps = |x: u32, y: u32, z: u32| test.overlaps(UVec3::new(x, y, z).as_dvec3() + DVec3::splat(0.5));
    let large = g.hi.x - g.lo.x >= BOUNDED_ROWS_FROM;
    for z in z_range {
        for y in g.lo.y..=g.hi.y {
            // The row's overlapped cells are a run (see the module doc): its first and last
            // are found by testing inward from both ends, and the cells between are taken. A
            // large triangle's row starts from the bounds the test's axes put on the run.
            let (mut x0, mut x1) = (g.lo.x, g.hi.x);
            if large {
                let Some((a, b)) = test.row_bounds(y as f64 + 0.5, z as f64 + 0.5) else { continue };
                let (a, b) = ((a - 0.5).floor().max(x0 as f64), (b - 0.5).ceil().min(x1 as f64));
                if a > b {
                    continue;
                }
                (x0, x1) = (a as u32, b as u32);
            }
            let Some(x0) = (x0..=x1).find(|&x| overlaps(x, y, z)) else { continue };
            let x1 = (x0 + 1..=x1).rev().find(|&x| overlaps(x, y, z)).unwrap_or(x0);
            let row = geom.cell_index(UVec3::new(x0, y, z));
            f(row..row + (x1 - x0 + 1) as usize);
            n += x1 - x0 + 1;
        }
    }
    n
}

/// Candidate rows of more cells than this are bounded by [`OverlapTest::row_bounds`] before
/// testing: the scan from a row's ends costs a test per cell outside the run (for a large
/// slanted triangle, most of the row), the bounds about as much as a few tests.
const BOUNDED_ROWS_FROM: u32 = 16;

/// Bounding-box insertion of the cell range `[lo, hi]` (a [`prepare`]d triangle's), in the
/// z layers `layers`: `f(cells)` for each x row of the box, in increasing order; returns how
/// many cells.
#[inline]
pub fn for_each_box_run_in_layers(
    geom: &GridGeometry,
    [lo, hi]: [UVec3; 2],
    layers: std::ops::Range<u32>,
    mut f: impl FnMut(std::ops::Range<usize>),
) -> u32 {
    let mut n = 0;
    let len = (hi.x - lo.x + 1) as usize;
    for z in lo.z.max(layers.start)..(hi.z + 1).min(layers.end) {
        let mut row = geom.cell_index(UVec3::new(lo.x, lo.y, z));
        for _ in lo.y..hi.y + 1 {
            f(row..row + len);
            row += geom.res.x as usize;
            n += len as u32;
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
    OverlapTest::new(tri, h).overlaps(c)
}

/// The separating-axis test of one triangle against cubes of half size `h`, with what depends
/// on the triangle alone computed once (per axis: the triangle's projected interval and the
/// cube's projected radius), so that a cube costs a dot product and two comparisons per axis.
/// The axes: the nine edge × box-axis cross products (zero ones skipped), the triangle's normal
/// (its interval a single value) and, first, the box axes (the triangle's bounding box).
struct OverlapTest {
    lo: DVec3,
    hi: DVec3,
    h: f64,
    /// Axis, the triangle's projected interval [min, max], the cube's projected radius.
    axes: [(DVec3, f64, f64, f64); 10],
    n: usize,
}

impl OverlapTest {
    #[inline]
    fn new(v: &[DVec3; 3], h: f64) -> OverlapTest {
        let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
        let mut axes = [(DVec3::ZERO, 0.0, 0.0, 0.0); 10];
        let mut n = 0;
        let radius = |a: DVec3| h * (a.x.abs() + a.y.abs() + a.z.abs());
        for edge in e {
            for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                let a = axis.cross(edge);
                if a == DVec3::ZERO {
                    continue;
                }
                let p = [a.dot(v[0]), a.dot(v[1]), a.dot(v[2])];
                axes[n] = (a, p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]), radius(a));
                n += 1;
            }
        }
        // The plane: the cube within its projected radius of the corners' projections (a
        // degenerate triangle's zero normal never separates). All three corners, not the first
        // alone: for a triangle whose corners are (nearly) collinear the computed normal is
        // rounding noise, not perpendicular to the edges, and the first corner's plane missed
        // the far end of the segment (found by a differential fuzz: a lattice triangle with its
        // third corner at the midpoint of the others, hit at an end, was left out of its cells).
        let normal = e[0].cross(e[1]);
        let p = [normal.dot(v[0]), normal.dot(v[1]), normal.dot(v[2])];
        axes[n] = (normal, p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]), radius(normal));
        n += 1;
        OverlapTest { lo: v[0].min(v[1]).min(v[2]), hi: v[0].max(v[1]).max(v[2]), h, axes, n }
    }

    /// Bounds on the centers' x of the cubes at (·, `cy`, `cz`) that overlap the triangle, or
    /// `None` when none does. Each axis' condition is linear in the center's x, so it holds on
    /// an interval, and the run of overlapping cubes lies in their intersection. The bounds
    /// are widened by [`ROW_SLACK`] (far above their rounding), and an axis that hardly depends
    /// on x (where solving for x would amplify the rounding) bounds nothing, so no cube that
    /// [`OverlapTest::overlaps`] accepts is ever outside them. A row is refused outright only
    /// by conditions that do not depend on x, evaluated as `overlaps` evaluates them.
    #[inline]
    fn row_bounds(&self, cy: f64, cz: f64) -> Option<(f64, f64)> {
        let h = self.h;
        let (ly, lz, hy, hz) = (self.lo.y - cy, self.lo.z - cz, self.hi.y - cy, self.hi.z - cz);
        if ly > h || lz > h || hy < -h || hz < -h {
            return None;
        }
        let (mut lo, mut hi) = (self.lo.x - h, self.hi.x + h);
        for &(a, min, max, r) in &self.axes[..self.n] {
            if a.x == 0.0 {
                // The same operations as `overlaps` (its x term is an exact zero).
                let ac = a.dot(DVec3::new(0.0, cy, cz));
                if min - ac > r || max - ac < -r {
                    return None;
                }
                continue;
            }
            if a.x.abs() < 1e-3 * (a.y.abs() + a.z.abs()) {
                continue;
            }
            // min − a·c ≤ r and max − a·c ≥ −r, with a·c = a.x·x + rest.
            let rest = a.y * cy + a.z * cz;
            let (p, q) = ((min - r - rest) / a.x, (max + r - rest) / a.x);
            let (p, q) = if a.x > 0.0 { (p, q) } else { (q, p) };
            lo = lo.max(p);
            hi = hi.min(q);
        }
        Some((lo - ROW_SLACK, hi + ROW_SLACK))
    }

    /// Whether the cube at `c` overlaps (or touches) the triangle.
    #[inline]
    fn overlaps(&self, c: DVec3) -> bool {
        let (lo, hi, h) = (self.lo - c, self.hi - c, self.h);
        if lo.x > h || lo.y > h || lo.z > h || hi.x < -h || hi.y < -h || hi.z < -h {
            return false;
        }
        self.axes[..self.n].iter().all(|&(a, min, max, r)| {
            let ac = a.dot(c);
            !(min - ac > r || max - ac < -r)
        })
    }
}

/// How far (in cells) [`OverlapTest::row_bounds`] widens its bounds.
const ROW_SLACK: f64 = 1e-6;

#[cfg(test)]
mod tests {
    use super::*;

    /// The vector cell range equals the scalar rule bit for bit: values on and near cell walls
    /// (within and beyond the margin), outside the grid on both sides, at its far wall, huge,
    /// infinite and NaN, on grids of 1 to 1024 cells an axis.
    #[test]
    fn vector_cell_range_equals_the_scalar_rule() {
        let margin = crate::geometry::INSERT_MARGIN_CELLS as f32;
        let mut xs = vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -1e30, 1e30, -0.0, 0.0, -0.5, f32::MIN_POSITIVE];
        for w in [0.0f32, 1.0, 2.0, 7.0, 16.0, 511.0, 1023.0, 1024.0, 1025.0] {
            for d in [0.0, margin, margin * 0.5, margin * 2.0, 1e-7, 1e-4, 0.5] {
                xs.extend([
                    w + d,
                    w - d,
                    f32::from_bits((w + d).to_bits() + 1),
                    f32::from_bits((w - d).to_bits().max(1) - 1),
                ]);
            }
        }
        // A deterministic spread of fractions.
        let mut h = 0x9e37_79b9u32;
        for _ in 0..2000 {
            h ^= h << 13;
            h ^= h >> 17;
            h ^= h << 5;
            xs.push((h % 2_200_000) as f32 / 2000.0 - 50.0);
        }
        for res in [UVec3::new(1, 3, 1024), UVec3::new(17, 1024, 2), UVec3::new(1024, 1, 64)] {
            for (k, &x) in xs.iter().enumerate() {
                let (y, z) = (xs[(k * 7 + 3) % xs.len()], xs[(k * 13 + 5) % xs.len()]);
                let (lo, hi) = (Vec3A::new(x, y, z), Vec3A::new(z, x, y));
                assert_eq!(
                    grid_box_cells_a(lo, hi, res, margin),
                    grid_box_cells_scalar(lo, hi, res, margin),
                    "{lo:?} {hi:?} {res}"
                );
            }
        }
    }
}
