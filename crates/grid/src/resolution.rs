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
//!   5–8 cells per triangle while T(m) picks ~20 (a ½…2× sweep around it, 2026-12-02). w = 2
//!   cell steps per byte per triangle is the value that puts every swept optimum of the shared
//!   scenes within T's reach on this machine (the README has the sweeps; 1.5 until the
//!   traversal's per-cell costs dropped, 2026-12-04). Its Tinter is 0.35, not the survey's
//!   0.5 ([`MEMORY_AWARE_T_INTER`]): since a cell's triangles are pre-filtered eight at a time,
//!   a test costs less next to a step, and the sweeps' fastest m moved to 0.6–0.85× the
//!   choice made with 0.5 (2026-12-04).
//! - the DRAM tier ([`CostModel::dram_bytes`], 16 MiB, weight 8 in the memory-aware model): a
//!   grid that outgrows the caches pays main memory's latency on the walk's misses. On the
//!   shared scenes (auto grids of at most 15 MB) it changes nothing; on the 1M-triangle crowd,
//!   the 2.1M mountain and the 2.4M particles the sweep's fastest grid lay at 0.6–0.85× the m
//!   chosen without it, which it picks, with builds faster by as much (2026-12-04).
//! - ties toward the coarser grid ([`CostModel::tie_tolerance`], 3% in the memory-aware model):
//!   from the least T(m), each next coarser sample whose T(m) is within the tolerance of it is
//!   taken. Near its optimum T(m) is flat (one sample, a factor 1.13 in m, either side is within
//!   0.4–4% of it on the shared scenes but the Cornell box) and the sampled N_m is an estimate,
//!   so the least sample is not known to be the fastest; the coarser one is known to be smaller
//!   and to build faster. A sweep of 2026-12-06 had the fastest m below the least sample on seven
//!   of nine scenes.
//! - below the interval (bounding-box insertion): when the interval's coarsest sample is the one
//!   taken, T(m) may keep falling below it (long slivers, whose boxes cross many cells), so the
//!   curve is extended toward m = 1 until its coarsest sample is no longer taken. Exact
//!   insertion keeps the interval: a sliver's exact references grow with its length in cells,
//!   not its box's volume, so box N_m's fall below the interval does not hold for it (the
//!   README's levers table has both measured).
//! - exact insertion takes the resolution the auto policy picks for bounding-box insertion.
//!   With exact N_m the memory term shrinks and T(m) picks grids one sample finer on most
//!   scenes, which measured no faster (the engine's and the teapot's 7–15% slower) and up to
//!   1.4× larger; and counting exact N_m costs more than the build itself (the overlap test per
//!   candidate cell). The README's levers table has the measurements.

use glam::{Vec3, Vec3A};
use gridrt_scene::Aabb;
use serde::{Deserialize, Serialize};

use crate::geometry::{GridGeometry, INSERT_MARGIN_CELLS, MAX_AXIS_RES, padded_bounds};
use crate::insert::{InsertMode, cell_count, cell_lanes, prepare};
use wide::{f32x4, i32x4};

/// [`CostModel::memory_aware`]'s cache: grids of a few KiB (tens of triangles) pay almost no
/// memory term, grids of megabytes nearly all of it. Read the README's tables for the value.
pub const MEMORY_AWARE_CACHE_BYTES: f64 = (1024 * 1024) as f64;

/// [`CostModel::memory_aware`]'s Tinter (Tstep stays the survey's 0.1): a triangle test in
/// cell steps, now that a cell's triangles are pre-filtered eight at a time. Read the README's
/// tables for the sweeps behind the value.
pub const MEMORY_AWARE_T_INTER: f64 = 0.35;

/// [`CostModel::memory_aware`]'s DRAM tier: the bytes of grid beyond which a walk's misses go to
/// main memory, and their weight (cell steps per byte per triangle, on top of the memory
/// weight). Every shared scene's auto grid is below it; the 1M-triangle crowd, the 2.1M
/// mountain and the 2.4M particles (58–166 MB) are above, and their swept optima lie at
/// 0.6–0.85× the m chosen without it. Read the README's tables for the values.
pub const MEMORY_AWARE_DRAM_BYTES: f64 = (16 * 1024 * 1024) as f64;
pub const MEMORY_AWARE_DRAM_WEIGHT: f64 = 8.0;

/// [`CostModel::memory_aware`]'s tie tolerance: from the least T(m), each next coarser sample
/// within this fraction of it is taken. The sampled N_m behind T(m) is an estimate within about
/// 2% of the exact count and the model leaves costs out, so a finer grid that it prices a few
/// percent cheaper is not known to be faster, while it is known to cost more memory and build
/// time. Read the README's tables for the sweeps behind the value.
pub const MEMORY_AWARE_TIE_TOLERANCE: f64 = 0.03;

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
    /// Bytes of grid the cache holds: the memory term is scaled by B / (B + cache_bytes) for a
    /// grid of B bytes, so a grid far smaller than the cache costs next to no misses and one far
    /// larger the whole term (0: the whole term at every size).
    #[serde(default)]
    pub cache_bytes: f64,
    /// Bytes of grid beyond which the walk's misses go to DRAM: every byte beyond them costs
    /// `dram_weight` cell steps per triangle more (0 weight: no such tier).
    #[serde(default)]
    pub dram_bytes: f64,
    #[serde(default)]
    pub dram_weight: f64,
    /// Samples whose T(m) is within this fraction of the least count as ties, broken toward
    /// the coarsest grid (0: the least T(m), the survey's rule).
    #[serde(default)]
    pub tie_tolerance: f64,
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
            cache_bytes: 0.0,
            dram_bytes: 0.0,
            dram_weight: 0.0,
            tie_tolerance: 0.0,
        }
    }
}

impl CostModel {
    /// The survey's constants with the memory term and a cheaper triangle test (see the module
    /// doc).
    /// Its interval, from M = N to the memory cap (64 cells per triangle), is narrower than the
    /// survey's in m, so 12 samples space m as finely as 24 do there (each sample is a counting
    /// pass, the largest part of a mid-size build).
    pub fn memory_aware() -> CostModel {
        CostModel {
            t_inter: MEMORY_AWARE_T_INTER,
            memory_weight: 2.0,
            samples: 12,
            cache_bytes: MEMORY_AWARE_CACHE_BYTES,
            dram_bytes: MEMORY_AWARE_DRAM_BYTES,
            dram_weight: MEMORY_AWARE_DRAM_WEIGHT,
            tie_tolerance: MEMORY_AWARE_TIE_TOLERANCE,
            ..CostModel::default()
        }
    }

    /// T(m) for a grid with `cells` cells and `n_m` triangle–cell references over `triangles`
    /// triangles, plus the memory term: 4.125 bytes per cell and 4 per reference, the flat
    /// grid's bytes when every cell had an offset. The flat grid now stores offsets for its
    /// occupied cells only (a quarter of a byte per empty cell), but the term stays as it was
    /// calibrated: it stands for the walk's cache misses per cell, which the sweep measures.
    /// The bytes beyond [`CostModel::dram_bytes`] weigh `dram_weight` more.
    pub fn cost(&self, cells: u64, n_m: u64, triangles: usize) -> f64 {
        let m = (cells as f64).cbrt();
        let bytes = 4.125 * cells as f64 + 4.0 * n_m as f64;
        let missed = bytes / (bytes + self.cache_bytes);
        let beyond = (bytes - self.dram_bytes).max(0.0);
        let per_tri = triangles.max(1) as f64;
        self.t_setup
            + m * self.t_step
            + (n_m as f64 / (m * m)) * self.t_inter
            + self.t_step * (self.memory_weight * missed * bytes + self.dram_weight * beyond) / per_tri
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

/// Chooses the resolution for `tris` within `bounds` for a grid of insertion `insert`: the
/// auto policy samples T(m) with bounding-box insertion's N_m whatever the grid's insertion, and
/// goes below its interval for bounding-box insertion only (see the module doc).
pub fn choose(
    tris: &[[Vec3; 3]],
    bounds: &Aabb,
    policy: Resolution,
    model: &CostModel,
    insert: InsertMode,
    parallel: bool,
) -> ResolutionChoice {
    choose_with(tris, bounds, None, policy, model, insert, parallel)
}

/// [`choose`] with the bounds pass's [`ChunkExtents`] (the same choice, fewer triangles read).
pub fn choose_with(
    tris: &[[Vec3; 3]],
    bounds: &Aabb,
    extents: Option<&ChunkExtents>,
    policy: Resolution,
    model: &CostModel,
    insert: InsertMode,
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
            let resolutions = sample_resolutions(tris.len(), bounds, model);
            let count =
                |r: &[[u32; 3]]| count_refs_curve_with(tris, bounds, extents, r, InsertMode::BoundingBox, parallel).0;
            let curve = costed(tris.len(), model, &resolutions, count(&resolutions));
            let curve = extended_below(curve, insert, tris.len(), bounds, model, count);
            let best = model.best_sample(&curve).expect("at least one sample");
            return ResolutionChoice { resolution: best.resolution, policy, curve };
        }
    };
    ResolutionChoice { resolution, policy, curve: Vec::new() }
}

impl CostModel {
    /// The sample guess-and-check takes among those a grid can hold (at most
    /// [`crate::build::MAX_REFS`] references; for long slivers the model's optimum can lie far
    /// beyond it): the least T(m), then each next coarser sample as long as its T(m) stays
    /// within [`CostModel::tie_tolerance`] of the least (a flat basin, not a distant dip of a
    /// curve that is not convex); with none buildable, the coarsest sample. `curve` is in
    /// increasing m, as [`sample_curve`] returns it. `None` for an empty curve.
    pub fn best_sample<'a>(&self, curve: &'a [CostSample]) -> Option<&'a CostSample> {
        let buildable = |s: &CostSample| s.n_m <= crate::build::MAX_REFS;
        let Some((mut i, least)) =
            curve.iter().enumerate().filter(|(_, s)| buildable(s)).min_by(|a, b| a.1.cost.total_cmp(&b.1.cost))
        else {
            return curve.iter().min_by_key(|s| s.cells);
        };
        let bound = least.cost * (1.0 + self.tie_tolerance.max(0.0));
        while i > 0 && buildable(&curve[i - 1]) && curve[i - 1].cost <= bound && curve[i - 1].cells < curve[i].cells {
            i -= 1;
        }
        Some(&curve[i])
    }
}

/// Above this many triangles, guess-and-check estimates N_m for bounding-box insertion from a
/// sample instead of counting every triangle at every sampled m (see [`count_refs_curve`]).
pub const EXACT_COUNT_LIMIT: usize = 1 << 12;

/// The constants of several grids (four a vector) for counting the cells of a triangle's
/// bounding box in each, one axis of four grids at a time.
#[derive(Clone, Debug)]
struct BoxCounter {
    /// Per group of four grids and per axis, the cells per unit of length, and the cells.
    inv: Vec<[f32x4; 3]>,
    res: Vec<[i32x4; 3]>,
}

impl BoxCounter {
    fn new(grids: &[GridGeometry]) -> BoxCounter {
        let (mut inv, mut res) = (Vec::new(), Vec::new());
        for group in grids.chunks(4) {
            // Padding lanes: a grid of one cell, where every box covers one cell.
            inv.push(std::array::from_fn(|a| {
                f32x4::new(std::array::from_fn(|j| group.get(j).map_or(0.0, |g| g.inv_cell[a])))
            }));
            res.push(std::array::from_fn(|a| {
                i32x4::new(std::array::from_fn(|j| group.get(j).map_or(1, |g| g.res[a] as i32)))
            }));
        }
        BoxCounter { inv, res }
    }

    /// Adds the cells the bounding box `[lo, hi]` (relative to the grids' common corner) covers
    /// in each grid to `sums`: exactly [`prepare`]'s cells, by [`crate::insert::cell_lanes`], the
    /// rule of every build (the per-axis map to grid space rounds monotonically, so mapping the
    /// box's corners gives exactly the min and max of the mapped vertices).
    #[inline]
    fn add(&self, lo: Vec3, hi: Vec3, sums: &mut [u64]) {
        let m = INSERT_MARGIN_CELLS as f32;
        for (g, (inv, res)) in self.inv.iter().zip(&self.res).enumerate() {
            let mut cells = i32x4::splat(1);
            for a in 0..3 {
                // At most MAX_AXIS_RES cells an axis: the product fits in 31 bits.
                let l = cell_lanes(f32x4::splat(lo[a]) * inv[a], res[a], false, m);
                let h = cell_lanes(f32x4::splat(hi[a]) * inv[a], res[a], true, m);
                cells *= h - l + i32x4::splat(1);
            }
            for (s, c) in sums[4 * g..].iter_mut().zip(cells.to_array()) {
                *s += c as u64;
            }
        }
    }
}

/// Whether triangle `i` is in the 1-in-`stride` sample: a multiplicative hash of the index, so
/// that meshes whose triangle order is periodic (a height field's rows) are not sampled in step
/// with their period, as a systematic every-k-th sample would be.
#[inline]
fn sampled(i: usize, stride: usize) -> bool {
    ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32).is_multiple_of(stride as u64)
}

/// Strata of the sampled triangles by their widest extent at the coarsest resolution, in cells
/// with the margins: narrower than one cell ("small"), than four ("medium"); wider ones are
/// always counted exactly. Whole runs of mid-size triangles make a third stratum,
/// [`MEDIUM_RUNS`].
const STRATUM_WIDTH: [f32; 2] = [1.0, 4.0];
/// The stratum of the runs of [`COUNT_CHUNK`] triangles that are all narrower than four cells
/// but not all narrower than one ([`RunClass::Medium`]): such a run is read only for its
/// sample, so guess-and-check over a mesh of mid-size triangles (a scan, a terrain, crowded
/// particles) reads a sample, not the scene.
const MEDIUM_RUNS: usize = STRATUM_WIDTH.len();
const STRATA: usize = STRATUM_WIDTH.len() + 1;

/// A run of [`COUNT_CHUNK`] triangles by its widest extent at the coarsest resolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RunClass {
    /// Every triangle surely narrower than a cell (all in the "small" stratum).
    Small,
    /// Every triangle surely narrower than four cells, so none "large": the run is the
    /// [`MEDIUM_RUNS`] stratum's.
    Medium,
    /// Some triangle may be four cells wide or more: its triangles are taken one by one.
    Wide,
}

impl RunClass {
    /// The class of a run whose widest extent is `widest` at cells of size `1 / inv_cell`, with
    /// the margins and [`WIDEST_SLACK_CELLS`]: a triangle's width in [`count_refs_curve`] is
    /// measured from the grid's corner, which rounds differently from the run's `max − min`.
    fn of(widest: Vec3, inv_cell: Vec3) -> RunClass {
        let e =
            (widest * inv_cell).max_element() * (1.0 + 1e-5) + WIDEST_SLACK_CELLS + 2.0 * INSERT_MARGIN_CELLS as f32;
        if e < STRATUM_WIDTH[0] {
            RunClass::Small
        } else if e < STRATUM_WIDTH[1] {
            RunClass::Medium
        } else {
            RunClass::Wide
        }
    }
}

/// Partial sums of one pass of [`count_refs_curve`].
struct Tally {
    /// Counts of the large triangles at each resolution.
    large: Vec<u64>,
    /// Counts of each stratum's counted triangles at each resolution.
    sampled: [Vec<u64>; STRATA],
    /// Triangles in each stratum, and how many of them were counted.
    members: [u64; STRATA],
    counted: [u64; STRATA],
}

impl Tally {
    fn new(k: usize) -> Tally {
        Tally {
            large: vec![0; k],
            sampled: std::array::from_fn(|_| vec![0; k]),
            members: [0; STRATA],
            counted: [0; STRATA],
        }
    }

    fn merge(mut self, o: Tally) -> Tally {
        let add = |a: &mut Vec<u64>, b: &[u64]| a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        add(&mut self.large, &o.large);
        for s in 0..STRATA {
            add(&mut self.sampled[s], &o.sampled[s]);
            self.members[s] += o.members[s];
            self.counted[s] += o.counted[s];
        }
        self
    }
}

/// N_m at each of `resolutions` (increasing) for insertion `mode`, in one pass over the
/// triangles. Up to [`EXACT_COUNT_LIMIT`] triangles every count is exact. Above it, a triangle
/// narrower than one or four cells at the coarsest resolution (the "small" and "medium"
/// strata) is counted only if it falls in a hashed 1-in-k sample, and each
/// stratum's sample mean stands in for the rest of it (the others cost a bounding box and a
/// comparison); every wider ("large") triangle is always counted exactly, so the few big
/// triangles that dominate N_m in architectural scenes never depend on the sample. A run of
/// [`COUNT_CHUNK`] triangles that holds no large triangle and not only small ones is a stratum
/// of its own ([`MEDIUM_RUNS`], with every such run), whose triangles are not classified one by
/// one: only its sample is read. Returns the counts and how many triangles were counted.
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
    // The runs' widest extents decide the strata: computed here as the bounds pass would.
    let extents = (tris.len() > EXACT_COUNT_LIMIT).then(|| crate::triangle_bounds_and_extents(tris, parallel).1);
    count_refs_curve_with(tris, bounds, extents.as_ref(), resolutions, mode, parallel)
}

/// Triangles per run of the bounds pass's [`ChunkExtents`] and of [`count_refs_curve`]'s work.
pub const COUNT_CHUNK: usize = 8192;

/// Per run of [`COUNT_CHUNK`] triangles (in order), the widest of its triangles' extents on each
/// axis (`max − min` of its corners, in f32; [`Aabb::of_triangles_and_widest`]):
/// [`crate::triangle_bounds_and_extents`]' by-product.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ChunkExtents(pub Vec<Vec3>);

/// Cells of slack on a run's widest extent before all of its triangles are taken as narrower
/// than a cell: a triangle's width in [`count_refs_curve`] is measured from the grid's corner
/// (`(max − corner) − (min − corner)`), which can round differently from `max − min`, by at
/// most a few ulps of the scene's extent (under 2·10⁻⁴ cells at 1024 cells an axis).
const WIDEST_SLACK_CELLS: f32 = 1e-3;

/// [`count_refs_curve`] with the bounds pass's [`ChunkExtents`] (the same counts): a run of
/// triangles all narrower than a cell at the coarsest resolution (all in the "small" stratum,
/// which is sampled), or of [`MEDIUM_RUNS`], is not read but for its sampled triangles. On
/// meshes of many small or mid-size triangles guess-and-check then reads a sample, not the
/// scene. Without extents (or with extents of other runs) above [`EXACT_COUNT_LIMIT`]
/// triangles, they are computed first.
pub fn count_refs_curve_with(
    tris: &[[Vec3; 3]],
    bounds: &Aabb,
    extents: Option<&ChunkExtents>,
    resolutions: &[[u32; 3]],
    mode: InsertMode,
    parallel: bool,
) -> (Vec<u64>, usize) {
    if resolutions.is_empty() || tris.len() <= EXACT_COUNT_LIMIT {
        return count_curve::<false>(tris, bounds, &[], resolutions, mode, parallel);
    }
    let computed;
    let extents = match extents.filter(|e| e.0.len() == tris.len().div_ceil(COUNT_CHUNK)) {
        Some(e) => &e.0,
        None => {
            computed = crate::triangle_bounds_and_extents(tris, parallel).1;
            &computed.0
        }
    };
    let inv_cell = GridGeometry::new(bounds, resolutions[0]).inv_cell;
    let classes: Vec<RunClass> = extents.iter().map(|w| RunClass::of(*w, inv_cell)).collect();
    // Without a run to skip, the counting loop compiled without the skipping (the branch alone
    // made it 1.4× slower on the 2.4M particles when none of their runs was skipped).
    if classes.iter().any(|&c| c != RunClass::Wide) {
        return count_curve::<true>(tris, bounds, &classes, resolutions, mode, parallel);
    }
    count_curve::<false>(tris, bounds, &classes, resolutions, mode, parallel)
}

/// [`count_refs_curve_with`]; `SKIP`: runs of small triangles and [`MEDIUM_RUNS`] (by
/// `classes`, one per run) are read only for their sample.
fn count_curve<const SKIP: bool>(
    tris: &[[Vec3; 3]],
    bounds: &Aabb,
    classes: &[RunClass],
    resolutions: &[[u32; 3]],
    mode: InsertMode,
    parallel: bool,
) -> (Vec<u64>, usize) {
    let grids: Vec<GridGeometry> = resolutions.iter().map(|&r| GridGeometry::new(bounds, r)).collect();
    let boxes = BoxCounter::new(&grids);
    // Adds the cells triangle `t` (box `[lo, hi]` relative to the grid corner) goes into at
    // each resolution to `sums`.
    let count = |t: &[Vec3; 3], lo: Vec3, hi: Vec3, sums: &mut [u64]| match mode {
        InsertMode::BoundingBox => boxes.add(lo, hi, sums),
        InsertMode::Exact => {
            for (g, s) in grids.iter().zip(sums) {
                *s += cell_count(g, &prepare(g, t, INSERT_MARGIN_CELLS), mode);
            }
        }
    };
    let k = grids.len();
    if k == 0 {
        return (Vec::new(), tris.len());
    }
    let min = grids[0].min;
    let min_a = Vec3A::from(min);
    let stride = tris.len().div_ceil(EXACT_COUNT_LIMIT).max(1);
    // The stratum of the box `[lo, hi]`: small, medium, or `None` for large (always exact).
    let stratum = |lo: Vec3, hi: Vec3| {
        if stride == 1 {
            return None;
        }
        let e = ((hi - lo) * grids[0].inv_cell).max_element() + 2.0 * INSERT_MARGIN_CELLS as f32;
        STRATUM_WIDTH.iter().position(|&w| e < w)
    };
    // Run `i`'s class, where runs are classed (above the exact-count limit).
    let class = |i: usize| if stride > 1 { classes.get(i).copied().unwrap_or(RunClass::Wide) } else { RunClass::Wide };
    // `exact[s]`: stratum s is counted exactly (all of it) rather than sampled; `large`: the
    // large triangles are counted.
    let tally = |exact: [bool; STRATA], large: bool, base: usize, part: &[[Vec3; 3]]| {
        let mut t = Tally::new(k);
        for (j, tri) in part.iter().enumerate() {
            // On SIMD lanes (the same operations per lane as `Vec3`'s): a run with wide
            // triangles is read whole, and its scalar minima and maxima were a seventh of the
            // engine's guess-and-check.
            let v = tri.map(Vec3A::from);
            let lo = Vec3::from(v[0].min(v[1]).min(v[2]) - min_a);
            let hi = Vec3::from(v[0].max(v[1]).max(v[2]) - min_a);
            let (sum, n) = match stratum(lo, hi) {
                None if !large => continue,
                None => (&mut t.large, None),
                Some(s) => {
                    t.members[s] += 1;
                    if !exact[s] && !sampled(base + j, stride) {
                        continue;
                    }
                    (&mut t.sampled[s], Some(s))
                }
            };
            count(tri, lo, hi, sum);
            if let Some(s) = n {
                t.counted[s] += 1;
            }
        }
        t
    };
    let run = |exact: [bool; STRATA], large: bool| -> Tally {
        const CHUNK: usize = COUNT_CHUNK;
        let each = |(i, p): (usize, &[[Vec3; 3]])| {
            // Only the sample of a run of small triangles is read (and counted as the stratum's
            // sample, exactly); the others are counted as its members. One call of `tally`,
            // which stays inlined: a second call made the counting loop 2× slower.
            if !SKIP {
                return tally(exact, large, i * CHUNK, p);
            }
            let pick = || (0..p.len()).filter(|&j| sampled(i * CHUNK + j, stride)).map(|j| p[j]).collect::<Vec<_>>();
            match class(i) {
                RunClass::Small if !exact[0] => {
                    let picked = pick();
                    let mut ex = exact;
                    ex[0] = true;
                    let mut t = tally(ex, large, 0, &picked);
                    t.members[0] += (p.len() - picked.len()) as u64;
                    t
                }
                // A run of the medium-run stratum: its sample (or all of it, when the stratum
                // is counted exactly), never classified triangle by triangle.
                RunClass::Medium => {
                    let mut t = Tally::new(k);
                    let picked;
                    let part = if exact[MEDIUM_RUNS] {
                        p
                    } else {
                        picked = pick();
                        &picked[..]
                    };
                    for tri in part {
                        let lo = tri[0].min(tri[1]).min(tri[2]) - min;
                        let hi = tri[0].max(tri[1]).max(tri[2]) - min;
                        count(tri, lo, hi, &mut t.sampled[MEDIUM_RUNS]);
                    }
                    t.members[MEDIUM_RUNS] = p.len() as u64;
                    t.counted[MEDIUM_RUNS] = part.len() as u64;
                    t
                }
                _ => tally(exact, large, i * CHUNK, p),
            }
        };
        #[cfg(feature = "parallel")]
        if parallel {
            use rayon::prelude::*;
            return tris.par_chunks(CHUNK).enumerate().map(each).reduce(|| Tally::new(k), Tally::merge);
        }
        let _ = parallel;
        tris.chunks(CHUNK).enumerate().map(each).fold(Tally::new(k), Tally::merge)
    };
    let mut t = run([false; STRATA], true);
    // A stratum with members but none in the sample (a few triangles of a rare size) is counted
    // exactly in a second pass that skips the others.
    let thin = std::array::from_fn(|s| t.counted[s] == 0 && t.members[s] > 0);
    if thin.contains(&true) {
        let again = run(thin, false);
        for s in (0..STRATA).filter(|&s| thin[s]) {
            t.sampled[s] = again.sampled[s].clone();
            t.counted[s] = again.counted[s];
        }
    }
    let counts = (0..k)
        .map(|i| {
            let estimate: f64 = (0..STRATA)
                .filter(|&s| t.counted[s] > 0)
                .map(|s| t.sampled[s][i] as f64 * t.members[s] as f64 / t.counted[s] as f64)
                .sum();
            t.large[i] + estimate.round() as u64
        })
        .collect();
    let counted = (tris.len() as u64 - t.members.iter().sum::<u64>() + t.counted.iter().sum::<u64>()) as usize;
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
    let resolutions = sample_resolutions(tris.len(), bounds, model);
    let curve = samples_at(tris, bounds, model, &resolutions, mode, parallel);
    extended_below(curve, mode, tris.len(), bounds, model, |r| count_refs_curve(tris, bounds, r, mode, parallel).0)
}

/// `curve` extended below its interval, for a grid of insertion `insert` when that is
/// bounding-box insertion, while its coarsest sample is the one [`CostModel::best_sample`]
/// takes and coarser grids exist: T(m) may keep falling there (long slivers, whose boxes cross
/// many cells at m = ∛N, cost least with far fewer cells). Each round samples `model.samples / 2` more m geometrically from an eighth
/// of the coarsest m (at least 1) up to below it, with `count` giving their N_m in one pass; the
/// rounds stop at m = 1. Exact insertion keeps the interval (see the module doc).
fn extended_below(
    mut curve: Vec<CostSample>,
    insert: InsertMode,
    triangles: usize,
    bounds: &Aabb,
    model: &CostModel,
    count: impl Fn(&[[u32; 3]]) -> Vec<u64>,
) -> Vec<CostSample> {
    if insert == InsertMode::Exact {
        return curve;
    }
    loop {
        let Some(first) = curve.first() else { return curve };
        if model.best_sample(&curve).map(|s| s.cells) != Some(first.cells) || first.cells <= 1 {
            return curve;
        }
        let (top, k) = (first.m, (model.samples / 2).max(2));
        let bottom = (top / 8.0).max(1.0);
        // Distinct resolutions in increasing cells, all coarser than the curve's first.
        let (mut below, mut below_cells): (Vec<[u32; 3]>, u64) = (Vec::new(), 0);
        for i in 0..k {
            let m = bottom * (top / bottom).powf(i as f64 / k as f64);
            let res = cubic_cells(bounds, m * m * m);
            let cells = cells_of(&res);
            if below_cells < cells && cells < first.cells {
                below.push(res);
                below_cells = cells;
            }
        }
        if below.is_empty() {
            return curve;
        }
        let counts = count(&below);
        let mut extended = costed(triangles, model, &below, counts);
        extended.append(&mut curve);
        curve = extended;
    }
}

/// The resolutions [`sample_curve`] samples for `triangles` triangles within `bounds`.
fn sample_resolutions(triangles: usize, bounds: &Aabb, model: &CostModel) -> Vec<[u32; 3]> {
    let n = triangles.max(1) as f64;
    let r = model.t_inter / model.t_step;
    // The survey's interval starts at the point model's optimum; with the memory term it starts
    // at one cell per triangle.
    let m_lo = if model.memory_weight > 0.0 { n.cbrt() } else { (2.0 * r * n).cbrt() }.max(1.0);
    let m_hi = (r * n).sqrt().min((model.cell_cap(triangles) as f64).cbrt()).max(m_lo);
    let k = model.samples.max(2);
    let mut resolutions: Vec<[u32; 3]> = Vec::new();
    for i in 0..k {
        let m = m_lo * (m_hi / m_lo).powf(i as f64 / (k - 1) as f64);
        let res = cubic_cells(bounds, m * m * m);
        if !resolutions.contains(&res) {
            resolutions.push(res);
        }
    }
    resolutions
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
    costed(tris.len(), model, resolutions, counts)
}

/// The cells of a resolution.
fn cells_of(res: &[u32; 3]) -> u64 {
    res.iter().map(|&x| x as u64).product()
}

/// The curve's samples from their resolutions and N_m.
fn costed(triangles: usize, model: &CostModel, resolutions: &[[u32; 3]], counts: Vec<u64>) -> Vec<CostSample> {
    resolutions
        .iter()
        .zip(counts)
        .map(|(&res, n_m)| {
            let cells = cells_of(&res);
            let mg = (cells as f64).cbrt();
            CostSample {
                m: mg,
                resolution: res,
                cells,
                n_m,
                mu: n_m as f64 / (mg * mg),
                cost: model.cost(cells, n_m, triangles),
            }
        })
        .collect()
}
