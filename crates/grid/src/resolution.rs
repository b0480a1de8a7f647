//! Choosing the grid resolution (survey §1, §3.2, §3.3).
//!
//! Cells are kept near-cubic on non-cubic scenes: a target cell count M gives a cell side
//! s = ∛(V/M), and each axis gets round(extent/s) cells (at least 1, at most
//! [`MAX_AXIS_RES`]). "m" below is the survey's cells-per-axis, generalised to ∛M for
//! non-cubic grids.
//!
//! Policies:
//! - fixed: `m=N` (longest axis gets N cells) or explicit `mx,my,mz`;
//! - density λ (Cleary/Ize): M = λN;
//! - point model (eq. 1): T = Tsetup + m·Tstep + (N/m²)·Tinter is minimal at
//!   M = m³ = 2N·Tinter/Tstep;
//! - line model (eq. 2): with μ = N/m, the minimum is at m = (N·Tinter/Tstep)^½, so
//!   M = (N·Tinter/Tstep)^{3/2}. (The survey's text prints the exponent as 1/3 but states
//!   the O(N^1.5) result; the derivation gives 1/2 for m, i.e. 3/2 for M.)
//! - cost-model guess-and-check (§3.3, the default): N_m is counted (same insertion as the
//!   build; exactly up to [`EXACT_COUNT_LIMIT`] triangles, above it with the large triangles
//!   exact and the small ones from a systematic sample) for sampled m in the survey's interval [m_point, m_line] — the two model
//!   optima, (10N)^⅓ … (5N)^½ with the default constants — each in linear time, and the m
//!   minimising T(m) = Tsetup + m·Tstep + (N_m/m²)·Tinter is taken. The sampled curve is
//!   returned for plotting. The interval's top is capped by a memory budget
//!   ([`CostModel::max_cells`]).
//! - memory-aware guess-and-check ([`CostModel::memory_aware`], the command line's and the
//!   app's auto): T(m) + Tstep·w·(bytes of the grid per triangle), sampled from M = N up. The
//!   survey's model ignores what a cell costs in memory; on the CPU the fastest flat grid has
//!   5–8 cells per triangle while T(m) picks ~20 (a ½…2× sweep around it, 2026-12-02). w = 1.5
//!   cell steps per byte per triangle is the value that puts every swept optimum of the shared
//!   scenes within T's reach on this machine (the README has the sweep).

use glam::Vec3;
use gridrt_scene::Aabb;
use serde::{Deserialize, Serialize};

use crate::geometry::{GridGeometry, INSERT_MARGIN_CELLS, MAX_AXIS_RES, padded_bounds};
use crate::insert::{InsertMode, cell_count, prepare};

/// The constants of T = Tsetup + m·Tstep + μ·Tinter, plus the guess-and-check settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CostModel {
    pub t_setup: f64,
    pub t_step: f64,
    pub t_inter: f64,
    /// Number of m values sampled by guess-and-check.
    pub samples: u32,
    /// Memory cap on the sampled interval: at most this many cells per triangle …
    pub max_cells_per_triangle: f64,
    /// … and at most this many cells overall. Also the hard limit for every structure, whatever
    /// chose its resolution (over all levels of a hierarchy): `--max-cells`.
    pub max_cells: u64,
    /// Memory weight w: cell steps' worth of time per byte of grid per triangle (0: the
    /// survey's model and interval).
    #[serde(default)]
    pub memory_weight: f64,
}

impl Default for CostModel {
    /// The survey's example constants (§3.3): Tsetup ≈ 1.0, Tstep ≈ 0.1, Tinter ≈ 0.5.
    fn default() -> CostModel {
        CostModel {
            t_setup: 1.0,
            t_step: 0.1,
            t_inter: 0.5,
            samples: 24,
            max_cells_per_triangle: 64.0,
            max_cells: 1 << 26,
            memory_weight: 0.0,
        }
    }
}

impl CostModel {
    /// The survey's constants with the memory term (see the module doc).
    /// Its interval, from M = N to the memory cap (64 cells per triangle), is narrower than the
    /// survey's in m, so 12 samples space m as finely as 24 do there (each sample is a counting
    /// pass, the largest part of a mid-size build).
    pub fn memory_aware() -> CostModel {
        CostModel { memory_weight: 1.5, samples: 12, ..CostModel::default() }
    }

    /// T(m) for a grid with `cells` cells and `n_m` triangle–cell references over `triangles`
    /// triangles, plus the memory term (the flat grid's bytes: an offset and an occupancy bit
    /// per cell, an index per reference).
    pub fn cost(&self, cells: u64, n_m: u64, triangles: usize) -> f64 {
        let m = (cells as f64).cbrt();
        let bytes = 4.125 * cells as f64 + 4.0 * n_m as f64;
        self.t_setup
            + m * self.t_step
            + (n_m as f64 / (m * m)) * self.t_inter
            + self.t_step * self.memory_weight * bytes / triangles.max(1) as f64
    }

    /// The memory cap on cells for `n` triangles.
    pub fn cell_cap(&self, n: usize) -> u64 {
        ((n as f64 * self.max_cells_per_triangle) as u64).max(4096).min(self.max_cells)
    }
}

/// How to choose the resolution (`--resolution`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Resolution {
    /// Cost-model guess-and-check (§3.3).
    Auto,
    /// M = λN cells.
    Density(f64),
    /// Point model, eq. (1).
    Point,
    /// Line model, eq. (2).
    Line,
    /// m cells along the longest axis, near-cubic cells.
    Cubic(u32),
    /// Exactly mx × my × mz.
    Explicit([u32; 3]),
}

impl std::str::FromStr for Resolution {
    type Err = String;
    /// `auto | density=λ | point | line | m=N | mx,my,mz`
    fn from_str(s: &str) -> Result<Resolution, String> {
        let s = s.trim();
        let bad = || format!("bad resolution \"{s}\": expected auto, density=λ, point, line, m=N or mx,my,mz");
        match s {
            "auto" => return Ok(Resolution::Auto),
            "point" => return Ok(Resolution::Point),
            "line" => return Ok(Resolution::Line),
            _ => {}
        }
        if let Some(v) = s.strip_prefix("density=") {
            let l: f64 = v.parse().map_err(|_| bad())?;
            return if l.is_finite() && l > 0.0 { Ok(Resolution::Density(l)) } else { Err(bad()) };
        }
        if let Some(v) = s.strip_prefix("m=") {
            let m: u32 = v.parse().map_err(|_| bad())?;
            return if (1..=MAX_AXIS_RES).contains(&m) {
                Ok(Resolution::Cubic(m))
            } else {
                Err(format!("m must be in 1..={MAX_AXIS_RES}"))
            };
        }
        let parts: Vec<&str> = s.split(',').collect();
        if parts.len() == 3 {
            let mut r = [0u32; 3];
            for (i, p) in parts.iter().enumerate() {
                r[i] = p.trim().parse().map_err(|_| bad())?;
                if !(1..=MAX_AXIS_RES).contains(&r[i]) {
                    return Err(format!("each of mx,my,mz must be in 1..={MAX_AXIS_RES}"));
                }
            }
            return Ok(Resolution::Explicit(r));
        }
        Err(bad())
    }
}

/// One sample of the guess-and-check curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CostSample {
    /// ∛(cells): the survey's m.
    pub m: f64,
    pub resolution: [u32; 3],
    pub cells: u64,
    /// Triangle–cell references N_m for the chosen insertion mode (exact up to
    /// [`EXACT_COUNT_LIMIT`] triangles, else an estimate; see [`count_refs_curve`]).
    pub n_m: u64,
    /// μ = N_m / m².
    pub mu: f64,
    /// Predicted T(m).
    pub cost: f64,
}

/// The chosen resolution, and the sampled curve when the cost model chose it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResolutionChoice {
    pub resolution: [u32; 3],
    pub policy: Resolution,
    pub curve: Vec<CostSample>,
}

/// Per-axis resolution with near-cubic cells and about `cells` cells over `bounds`.
pub fn cubic_cells(bounds: &Aabb, cells: f64) -> [u32; 3] {
    let ext = padded_bounds(bounds).extent();
    let volume = ext.x as f64 * ext.y as f64 * ext.z as f64;
    let side = (volume / cells.max(1.0)).cbrt();
    axis_res(ext, side)
}

fn axis_res(ext: Vec3, side: f64) -> [u32; 3] {
    [0, 1, 2].map(|a| ((ext[a] as f64 / side).round() as u32).clamp(1, MAX_AXIS_RES))
}

/// m cells along the longest axis of `bounds`, near-cubic cells on the others.
pub fn cubic_m(bounds: &Aabb, m: u32) -> [u32; 3] {
    let ext = padded_bounds(bounds).extent();
    axis_res(ext, ext.max_element() as f64 / m.max(1) as f64)
}

/// Number of references N_m the grid `res` would hold (linear time, no allocation beyond the
/// iteration).
pub fn count_refs(tris: &[[Vec3; 3]], bounds: &Aabb, res: [u32; 3], mode: InsertMode, parallel: bool) -> u64 {
    let geom = GridGeometry::new(bounds, res);
    let one = |t: &[Vec3; 3]| cell_count(&geom, &prepare(&geom, t, INSERT_MARGIN_CELLS), mode);
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        return tris.par_iter().map(one).sum();
    }
    let _ = parallel;
    tris.iter().map(one).sum()
}

/// Chooses the resolution for `tris` within `bounds`.
pub fn choose(
    tris: &[[Vec3; 3]],
    bounds: &Aabb,
    policy: Resolution,
    model: &CostModel,
    mode: InsertMode,
    parallel: bool,
) -> ResolutionChoice {
    let n = tris.len().max(1) as f64;
    let r = model.t_inter / model.t_step;
    let cap = model.cell_cap(tris.len()) as f64;
    let resolution = match policy {
        Resolution::Explicit(r) => r,
        Resolution::Cubic(m) => cubic_m(bounds, m),
        Resolution::Density(l) => cubic_cells(bounds, l * n),
        Resolution::Point => cubic_cells(bounds, (2.0 * n * r).min(cap)),
        Resolution::Line => cubic_cells(bounds, (n * r).powf(1.5).min(cap)),
        Resolution::Auto => {
            let curve = sample_curve(tris, bounds, model, mode, parallel);
            let best = best_sample(&curve).expect("at least one sample");
            return ResolutionChoice { resolution: best.resolution, policy, curve };
        }
    };
    ResolutionChoice { resolution, policy, curve: Vec::new() }
}

/// The sample guess-and-check takes: the least T(m) among those a grid can hold (at most
/// [`crate::build::MAX_REFS`] references; for long slivers the model's optimum can lie far
/// beyond it), else the coarsest. `None` for an empty curve.
pub fn best_sample(curve: &[CostSample]) -> Option<&CostSample> {
    curve
        .iter()
        .filter(|s| s.n_m <= crate::build::MAX_REFS)
        .min_by(|a, b| a.cost.total_cmp(&b.cost))
        .or_else(|| curve.iter().min_by_key(|s| s.cells))
}

/// Above this many triangles, guess-and-check estimates N_m for bounding-box insertion from a
/// sample instead of counting every triangle at every sampled m (see [`count_refs_curve`]).
pub const EXACT_COUNT_LIMIT: usize = 1 << 14;

/// A grid's constants for counting the cells of a triangle's bounding box.
#[derive(Clone, Copy, Debug)]
struct BoxCounter {
    inv: Vec3,
    res: glam::UVec3,
}

impl BoxCounter {
    fn new(geom: &GridGeometry) -> BoxCounter {
        BoxCounter { inv: geom.inv_cell, res: geom.res }
    }

    /// Cells the bounding box `[lo, hi]` covers, given relative to the grid's corner (`min` is
    /// the same at every resolution, so callers subtract it once). Exactly [`prepare`]'s cells:
    /// the per-axis map to grid space rounds monotonically, so mapping the box's corners gives
    /// exactly the min and max of the mapped vertices.
    #[inline]
    fn cells(&self, lo: Vec3, hi: Vec3) -> u64 {
        let [l, h] = crate::insert::grid_box_cells(lo * self.inv, hi * self.inv, self.res, INSERT_MARGIN_CELLS as f32);
        let e = h - l + glam::UVec3::ONE;
        e.x as u64 * e.y as u64 * e.z as u64
    }

    /// Whether the box is narrower than one cell (minus the margins) on every axis.
    #[inline]
    fn is_small(&self, lo: Vec3, hi: Vec3) -> bool {
        (((hi - lo) * self.inv).max_element() as f64) + 2.0 * INSERT_MARGIN_CELLS < 1.0
    }
}

/// Whether triangle `i` is in the 1-in-`stride` sample: a multiplicative hash of the index, so
/// that meshes whose triangle order is periodic (a height field's rows) are not sampled in step
/// with their period, as a systematic every-k-th sample would be.
#[inline]
fn sampled(i: usize, stride: usize) -> bool {
    ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32).is_multiple_of(stride as u64)
}

/// N_m at each of `resolutions` (increasing) for insertion `mode`, in one pass over the
/// triangles. Up to [`EXACT_COUNT_LIMIT`] triangles every count is exact. Above it, a triangle
/// narrower than a cell at the coarsest resolution ("small") is counted at the finer ones only
/// if it falls in a hashed 1-in-k sample, and the sample's mean stands in for the rest;
/// every other ("large") triangle is always counted exactly, so the few big triangles that
/// dominate N_m in architectural scenes never depend on the sample. The coarsest resolution's
/// count is always exact. Returns the counts and how many triangles were counted at every m.
///
/// Bounding-box counts come from the box alone; exact insertion runs the overlap test per
/// candidate cell (the same as the build), so for it the sample is what keeps guess-and-check
/// from costing several builds.
pub fn count_refs_curve(
    tris: &[[Vec3; 3]],
    bounds: &Aabb,
    resolutions: &[[u32; 3]],
    mode: InsertMode,
    parallel: bool,
) -> (Vec<u64>, usize) {
    let grids: Vec<GridGeometry> = resolutions.iter().map(|&r| GridGeometry::new(bounds, r)).collect();
    let geoms: Vec<BoxCounter> = grids.iter().map(BoxCounter::new).collect();
    // Cells triangle `t` (box `[lo, hi]` relative to the grid corner) goes into at resolution i.
    let count = |i: usize, t: &[Vec3; 3], lo: Vec3, hi: Vec3| match mode {
        InsertMode::BoundingBox => geoms[i].cells(lo, hi),
        InsertMode::Exact => cell_count(&grids[i], &prepare(&grids[i], t, INSERT_MARGIN_CELLS), mode),
    };
    let k = geoms.len();
    if k == 0 {
        return (Vec::new(), tris.len());
    }
    let min = grids[0].min;
    let stride = tris.len().div_ceil(EXACT_COUNT_LIMIT).max(1);
    // Per chunk: [exact counts of large and sampled small triangles ×k, small total, small
    // sampled, large count at the first resolution].
    let chunk = |base: usize, part: &[[Vec3; 3]]| {
        let mut large = vec![0u64; k];
        let mut small = vec![0u64; k];
        let (mut n_small, mut n_sampled) = (0u64, 0u64);
        for (j, t) in part.iter().enumerate() {
            let lo = t[0].min(t[1]).min(t[2]) - min;
            let hi = t[0].max(t[1]).max(t[2]) - min;
            let c0 = count(0, t, lo, hi);
            if stride > 1 && geoms[0].is_small(lo, hi) {
                n_small += 1;
                small[0] += c0;
                if sampled(base + j, stride) {
                    n_sampled += 1;
                    for (i, s) in small.iter_mut().enumerate().skip(1) {
                        *s += count(i, t, lo, hi);
                    }
                }
            } else {
                large[0] += c0;
                for (i, s) in large.iter_mut().enumerate().skip(1) {
                    *s += count(i, t, lo, hi);
                }
            }
        }
        (large, small, n_small, n_sampled)
    };
    const CHUNK: usize = 8192;
    let merge = |a: (Vec<u64>, Vec<u64>, u64, u64), b: (Vec<u64>, Vec<u64>, u64, u64)| {
        let add = |x: Vec<u64>, y: Vec<u64>| x.iter().zip(&y).map(|(p, q)| p + q).collect::<Vec<u64>>();
        (add(a.0, b.0), add(a.1, b.1), a.2 + b.2, a.3 + b.3)
    };
    let zero = || (vec![0u64; k], vec![0u64; k], 0u64, 0u64);
    #[cfg(feature = "parallel")]
    let (large, small, n_small, n_sampled) = if parallel {
        use rayon::prelude::*;
        tris.par_chunks(CHUNK).enumerate().map(|(i, p)| chunk(i * CHUNK, p)).reduce(zero, merge)
    } else {
        tris.chunks(CHUNK).enumerate().map(|(i, p)| chunk(i * CHUNK, p)).fold(zero(), merge)
    };
    #[cfg(not(feature = "parallel"))]
    let (large, small, n_small, n_sampled) = {
        let _ = parallel;
        tris.chunks(CHUNK).enumerate().map(|(i, p)| chunk(i * CHUNK, p)).fold(zero(), merge)
    };
    let counts = (0..k)
        .map(|i| {
            if i == 0 {
                large[0] + small[0]
            } else if n_sampled == 0 {
                // No small triangle fell in the sample (so there are few): each covers ≥ 1 cell.
                large[i] + n_small
            } else {
                large[i] + (small[i] as f64 * n_small as f64 / n_sampled as f64).round() as u64
            }
        })
        .collect();
    let counted = (tris.len() as u64 - n_small + n_sampled) as usize;
    (counts, counted)
}

/// T(m) sampled at `model.samples` geometrically spaced m in [m_point, m_line] (capped by
/// memory), distinct resolutions only, in increasing m. N_m is exact for exact insertion and
/// up to [`EXACT_COUNT_LIMIT`] triangles, else estimated (see [`count_refs_curve`]).
pub fn sample_curve(
    tris: &[[Vec3; 3]],
    bounds: &Aabb,
    model: &CostModel,
    mode: InsertMode,
    parallel: bool,
) -> Vec<CostSample> {
    let n = tris.len().max(1) as f64;
    let r = model.t_inter / model.t_step;
    // The survey's interval starts at the point model's optimum; with the memory term it starts
    // at one cell per triangle.
    let m_lo = if model.memory_weight > 0.0 { n.cbrt() } else { (2.0 * r * n).cbrt() }.max(1.0);
    let m_hi = (r * n).sqrt().min((model.cell_cap(tris.len()) as f64).cbrt()).max(m_lo);
    let k = model.samples.max(2);
    let mut resolutions: Vec<[u32; 3]> = Vec::new();
    for i in 0..k {
        let m = m_lo * (m_hi / m_lo).powf(i as f64 / (k - 1) as f64);
        let res = cubic_cells(bounds, m * m * m);
        if !resolutions.contains(&res) {
            resolutions.push(res);
        }
    }
    samples_at(tris, bounds, model, &resolutions, mode, parallel)
}

/// T(m) at the given resolutions (increasing), N_m counted as [`sample_curve`] does.
pub fn samples_at(
    tris: &[[Vec3; 3]],
    bounds: &Aabb,
    model: &CostModel,
    resolutions: &[[u32; 3]],
    mode: InsertMode,
    parallel: bool,
) -> Vec<CostSample> {
    let (counts, _) = count_refs_curve(tris, bounds, resolutions, mode, parallel);
    resolutions
        .iter()
        .zip(counts)
        .map(|(&res, n_m)| {
            let cells = res.iter().map(|&x| x as u64).product::<u64>();
            let mg = (cells as f64).cbrt();
            CostSample {
                m: mg,
                resolution: res,
                cells,
                n_m,
                mu: n_m as f64 / (mg * mg),
                cost: model.cost(cells, n_m, tris.len()),
            }
        })
        .collect()
}
