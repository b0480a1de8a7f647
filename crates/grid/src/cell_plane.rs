//! Cell slabs: per occupied cell of a flat grid, a slab `lo ≤ n · p ≤ hi` (grid space) that
//! holds every triangle of the cell; a ray whose segment in the cell stays on one side of it
//! cannot hit any of them there, and the cell's tests are skipped.
//!
//! A cell of a scanned or CAD surface holds a small patch of it, nearly flat: the slab along the
//! patch's mean normal is a small fraction of a cell thick, and most of the occupied cells a ray
//! crosses before its hit (near the silhouette, just above the surface) are passed by one check
//! instead of a dozen triangle tests. Not a survey technique: a lever of issue 16, measured in the
//! README's levers table.
//!
//! Exact: a skipped cell changes no hit. The closest-hit rule needs the hit triangle tested in
//! the cell whose walk interval holds the hit (see [`crate::trace::closest_hit`]); there the
//! segment passes through the hit point, which lies on the triangle, so inside its slab. The slab
//! is widened by the insertion margin ([`INSERT_MARGIN_CELLS`], in units of `n` with
//! `|n|₁ = 1`, so any point within the margin of the segment counts), the same allowance that
//! makes the insertion itself conservative, and each side is evaluated with a bound on its f32
//! rounding ([`CellRay::slack`]). Skipping a cell mailboxes nothing, so a triangle it holds is
//! still tested in a later cell.

use glam::{BVec3, UVec3, Vec3, Vec3A};
use serde::{Deserialize, Serialize};

use crate::flat::FlatGrid;
use crate::geometry::{GridRay, INSERT_MARGIN_CELLS};

/// Cells with fewer references are never checked: a check costs about two triangle tests'
/// pre-filter, which a cell of a few triangles does not repay (measured: the Cornell box and
/// the teapot's stadium got slower with every cell checked).
pub const PLANE_MIN_REFS: usize = 6;

/// Thickest slab kept, in cells (a cell is one cell thick along any `n` with `|n|₁ = 1`): a
/// thicker one, where a cell holds parts of differently oriented surfaces (architecture), is
/// crossed by most segments, so its check would cost more than it saves.
pub const MAX_SLAB_CELLS: f32 = 0.5;

/// Triangles of a cell whose normals make the slab's normal.
const NORMAL_SAMPLE: usize = 4;

/// A bound, in cells, on the f32 rounding of a slab's sides: corners mapped to grid space
/// (coordinates up to [`crate::geometry::MAX_AXIS_RES`], a few units in the last place, about
/// 10⁻⁴) and their products with `n` (`|n|₁ = 1`, as much again), with room to spare.
const SLAB_ROUNDING_CELLS: f32 = 1e-3;

/// [`CellPlanes::Auto`] gives a grid slabs when at least this share of its references lies in
/// cells of [`PLANE_MIN_REFS`] or more.
pub const PLANE_MIN_SHARE: f64 = 0.5;

/// Which grids get cell slabs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum CellPlanes {
    /// Macrocell grids and exact-insertion flat grids whose references mostly lie in cells of
    /// [`PLANE_MIN_REFS`] or more (not the bounding-box flat grid, which is the fast build that
    /// dynamic scenes rebuild every frame).
    #[default]
    Auto,
    /// Every flat and macrocell grid.
    On,
    /// None.
    Off,
}

impl CellPlanes {
    /// This policy for a grid traced by the CPU's single rays (`single_rays`) or not: slabs are
    /// read by single rays only, so under `Auto` packets and the GPU get none (`On` and `Off`
    /// stay as asked).
    pub fn for_tracing(self, single_rays: bool) -> CellPlanes {
        if self == CellPlanes::Auto && !single_rays { CellPlanes::Off } else { self }
    }
}

impl std::str::FromStr for CellPlanes {
    type Err = String;
    fn from_str(s: &str) -> Result<CellPlanes, String> {
        match s {
            "auto" => Ok(CellPlanes::Auto),
            "on" => Ok(CellPlanes::On),
            "off" => Ok(CellPlanes::Off),
            _ => Err(format!("bad cell planes \"{s}\": expected auto, on or off")),
        }
    }
}

/// A slab `lo ≤ n · p ≤ hi` in the grid's space (cells are unit cubes), `|n|₁ = 1`, widened by
/// the insertion margin. [`CellPlane::NONE`] for a cell that is not checked.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellPlane {
    pub n: [f32; 3],
    pub lo: f32,
    pub hi: f32,
}

impl CellPlane {
    /// No slab: the check never skips the cell.
    pub const NONE: CellPlane = CellPlane { n: [0.0; 3], lo: f32::NEG_INFINITY, hi: f32::INFINITY };

    /// The thinner of two slabs holding the triangles `refs` of `tris` (mapped to grid space by
    /// `to_grid`): along the area-weighted normal of the first few, and along the axis of the
    /// least extent. In f32, widened by the insertion margin and by [`SLAB_ROUNDING_CELLS`].
    fn of(refs: &[u32], tris: &[[Vec3; 3]], to_grid: impl Fn(Vec3) -> Vec3A) -> CellPlane {
        let corners = |t: u32| tris[t as usize].map(&to_grid);
        let normal: Vec3A = refs
            .iter()
            .take(NORMAL_SAMPLE)
            .map(|&t| {
                let [a, b, c] = corners(t);
                (b - a).cross(c - a)
            })
            .sum();
        let l1 = normal.abs().element_sum();
        let n = if l1 > 0.0 && l1.is_finite() { normal / l1 } else { Vec3A::X };
        let (mut lo, mut hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        let (mut a, mut b) = (f32::INFINITY, f32::NEG_INFINITY);
        for &t in refs {
            for v in corners(t) {
                lo = lo.min(v);
                hi = hi.max(v);
                // Selects, not `f32::min`'s NaN handling (a NaN is skipped either way: `a` and
                // `b` never are one), which had been a third of the loop.
                let d = n.dot(v);
                a = if d < a { d } else { a };
                b = if d > b { d } else { b };
            }
        }
        let e = hi - lo;
        let axis = if e.x <= e.y && e.x <= e.z {
            0
        } else if e.y <= e.z {
            1
        } else {
            2
        };
        let (n, lo, hi) = if e[axis] <= b - a { (Vec3A::AXES[axis], lo[axis], hi[axis]) } else { (n, a, b) };
        if !(lo.is_finite() && hi.is_finite() && hi - lo <= MAX_SLAB_CELLS) {
            return CellPlane::NONE;
        }
        let widen = INSERT_MARGIN_CELLS as f32 + SLAB_ROUNDING_CELLS;
        CellPlane { n: n.to_array(), lo: lo - widen, hi: hi + widen }
    }

    /// Whether the segment of `r` in cell `c`, from the cell's entry to `t_exit`, stays on one
    /// side of the slab (so no triangle of the cell is hit in it).
    #[inline(always)]
    pub fn misses(&self, r: &CellRay, c: UVec3, t_exit: f32) -> bool {
        // The entry: the latest crossing of the cell's near walls (the walk's own arithmetic),
        // or the segment's start.
        let wall = c.as_vec3() + r.lower;
        let t = Vec3::select(r.moving, (wall - r.o) * r.inv_d, Vec3::NEG_INFINITY);
        let t_in = r.t0.max(t.max_element());
        let n = Vec3::from_array(self.n);
        let (a, b) = (n.dot(r.o + r.d * t_in), n.dot(r.o + r.d * t_exit));
        a.max(b) < self.lo - r.slack || a.min(b) > self.hi + r.slack
    }
}

/// A ray's line in a grid's space, for [`CellPlane::misses`].
#[derive(Clone, Copy, Debug)]
pub struct CellRay {
    o: Vec3,
    d: Vec3,
    inv_d: Vec3,
    /// Per axis, the cell's entry wall relative to its lower corner (1 moving down).
    lower: Vec3,
    moving: BVec3,
    t0: f32,
    /// A bound on the f32 rounding of `n · (o + t·d)` over the segment (`|n|₁ = 1`): a few
    /// units in the last place of the largest coordinate met, with a factor of four to spare.
    slack: f32,
}

impl CellRay {
    #[inline(always)]
    pub fn new(g: &GridRay) -> CellRay {
        let reach = g.o.abs().max_element() + g.t0.abs().max(g.t1.abs()) * g.d.abs().max_element() + 1.0;
        CellRay {
            o: g.o,
            d: g.d,
            inv_d: g.inv_d,
            lower: Vec3::select(g.d.cmplt(Vec3::ZERO), Vec3::ONE, Vec3::ZERO),
            moving: g.d.cmpne(Vec3::ZERO),
            t0: g.t0,
            slack: reach * (1.0 / (1u32 << 20) as f32),
        }
    }
}

/// Whether `grid` gets slabs under `policy`: `eligible` says whether its kind and insertion do
/// (see [`CellPlanes::Auto`]).
pub fn wanted(grid: &FlatGrid, policy: CellPlanes, eligible: bool) -> bool {
    match policy {
        CellPlanes::Off => false,
        CellPlanes::On => true,
        CellPlanes::Auto => {
            eligible && {
                let in_big: u64 = grid
                    .ref_start
                    .windows(2)
                    .map(|w| (w[1] - w[0]) as u64)
                    .filter(|&n| n >= PLANE_MIN_REFS as u64)
                    .sum();
                in_big as f64 >= PLANE_MIN_SHARE * grid.refs.len() as f64
            }
        }
    }
}

/// Occupied cells whose slabs [`CellPlanes::Auto`] computes first, evenly spaced over the
/// grid, to estimate the share of references that would lie in cells with a slab: a grid that
/// falls short (architecture, whose cells mix walls and floors) is refused without computing
/// every slab (that had cost Sponza's macrocell build half again).
const COVERAGE_SAMPLE: usize = 4096;

/// The slab of each occupied cell of `grid` over `tris` (the triangles it was built from), in
/// the order of [`FlatGrid::ref_start`]; [`CellPlane::NONE`] for cells of fewer than
/// [`PLANE_MIN_REFS`] references or thicker than [`MAX_SLAB_CELLS`]. Under
/// [`CellPlanes::Auto`], none at all (an empty vector) unless the cells with a slab hold
/// [`PLANE_MIN_SHARE`] of the references of [`COVERAGE_SAMPLE`] cells spread over the grid
/// (every cell when there are no more).
pub fn planes_of(grid: &FlatGrid, tris: &[[Vec3; 3]], policy: CellPlanes, parallel: bool) -> Vec<CellPlane> {
    let (min, inv) = (Vec3A::from(grid.geom.min), Vec3A::from(grid.geom.inv_cell));
    let to_grid = |p: Vec3| (Vec3A::from(p) - min) * inv;
    let cells = grid.ref_start.len().saturating_sub(1);
    let plane = |j: usize| -> CellPlane {
        let refs = grid.refs_at(j);
        if refs.len() < PLANE_MIN_REFS {
            return CellPlane::NONE;
        }
        CellPlane::of(refs, tris, to_grid)
    };
    // Worth their check only where most references lie in cells with a slab: whether the
    // cells with one hold PLANE_MIN_SHARE of the references among `(cell, slab)`.
    let covers = |pairs: &mut dyn Iterator<Item = (usize, CellPlane)>| {
        let (covered, all) = pairs.fold((0u64, 0u64), |(c, a), (j, p)| {
            let n = grid.refs_at(j).len() as u64;
            (c + if p != CellPlane::NONE { n } else { 0 }, a + n)
        });
        covered as f64 >= PLANE_MIN_SHARE * all as f64
    };
    let stride = cells.div_ceil(COVERAGE_SAMPLE).max(1);
    let mut sample = Vec::new();
    if policy == CellPlanes::Auto && stride > 1 {
        sample = each_cell(cells.div_ceil(stride), parallel, |k| plane(k * stride));
        if !covers(&mut sample.iter().enumerate().map(|(k, &p)| (k * stride, p))) {
            return Vec::new();
        }
    }
    // The sampled cells' slabs are not computed again.
    let planes = each_cell(cells, parallel, |j| match sample.get(j / stride) {
        Some(&p) if j % stride == 0 => p,
        _ => plane(j),
    });
    // A grid of at most COVERAGE_SAMPLE occupied cells is its own sample.
    if policy == CellPlanes::Auto && stride == 1 && !covers(&mut planes.iter().copied().enumerate()) {
        return Vec::new();
    }
    planes
}

/// `f` of each of `0..n`, on all threads when `parallel` (and the `parallel` feature).
fn each_cell(n: usize, parallel: bool, f: impl Fn(usize) -> CellPlane + Sync + Send) -> Vec<CellPlane> {
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        return (0..n).into_par_iter().map(f).collect();
    }
    let _ = parallel;
    (0..n).map(f).collect()
}
