//! Interleaved walks: a batch's rays walk a flat, macrocell or proximity grid [`SLOTS`] at a time, each advancing one
//! stage per turn while the loads the others asked for are in flight.
//!
//! An occupied cell costs a chain of dependent loads: its offset in `ref_start`, then its
//! references, then their triangles. A ray that misses the cache at each link waits for all
//! three in turn, and nothing inside the cell can start them earlier. Here a ray that reaches an
//! occupied cell only asks for the offset (a prefetch) and yields; on its next turn, after the
//! other rays' turns, it reads the offset and asks for the references, then for the triangles,
//! and only then tests them. The loads of the rays in flight overlap, as a GPU's warps hide
//! their latency.
//!
//! Each ray's search is [`trace_flat`](super::trace_flat)'s, step for step: the same cells in
//! the same order ([`LinearWalk`] is the Amanatides–Woo walk of
//! [`crate::traversal::walk`]), the same [`ClosestHit`] tests and stopping rule, so the hits
//! and the stats are the same bit for bit.

use glam::{UVec3, Vec3};
use gridrt_scene::{Hit, Ray};

use super::closest_hit::{ClosestHit, prefetch};
use super::{TraceOptions, trace_each, trace_flat};
use crate::cell_plane::CellRay;
use crate::flat::FlatGrid;
use crate::geometry::GridRay;
use crate::macrocell::MacrocellGrid;
use crate::proximity::{Jump, ProximityGrid};
use crate::stats::{BatchStats, RayStats};
use crate::traversal::amanatides_woo::{AmanatidesWoo, LinearWalk};

/// Rays walking at once: enough turns between a prefetch and the load it serves to hide a miss
/// to the last-level cache.
pub const SLOTS: usize = 8;

/// Bytes of grid and triangles beyond which interleaving pays ([`trace_chunk`]): below,
/// the arrays stay in the core's cache and the turns only add work.
pub const INTERLEAVE_MIN_BYTES: u64 = 2 << 20;

/// Neighbouring pairs [`incoherent`] samples at most.
const COHERENCE_PAIRS: usize = 32;

/// Whether `rays` are incoherent: fewer than half of up to [`COHERENCE_PAIRS`] neighbouring pairs
/// (spread over the batch) point within about 25° of each other. Camera rays and shadow rays
/// from neighbouring pixels are coherent: one ray's cells are still in the cache for the next.
pub fn incoherent(rays: &[Ray]) -> bool {
    let pairs = rays.len().saturating_sub(1);
    let n = pairs.min(COHERENCE_PAIRS);
    if n == 0 {
        return false;
    }
    let stride = pairs / n;
    let close = (0..n)
        .filter(|&k| {
            let (a, b) = (rays[k * stride].d(), rays[k * stride + 1].d());
            a.dot(b) > 0.9 * a.length() * b.length()
        })
        .count();
    2 * close < n
}

/// Whether a chunk of `rays` through a structure of `bytes` (with its triangles) walks
/// interleaved: when the arrays outgrow the cache ([`INTERLEAVE_MIN_BYTES`]) and the rays are
/// [`incoherent`]. The hits and stats are the same either way.
pub fn pays(bytes: u64, rays: &[Ray]) -> bool {
    bytes > INTERLEAVE_MIN_BYTES && incoherent(rays)
}

/// A grid whose batches can walk interleaved: its walk to the next occupied cell, its bytes
/// (with [`pays`]) and its single-ray trace.
pub trait Interleave {
    type Walk<'g>: CellWalk
    where
        Self: 'g;
    /// The walk of `search`'s ray, or `None` when the ray misses the grid.
    fn walk<'g>(&'g self, search: &ClosestHit) -> Option<Self::Walk<'g>>;
    fn memory_bytes(&self) -> u64;
    /// The ray-by-ray trace the interleaved walk equals.
    fn trace_one(&self, tris: &[[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> (Hit, RayStats);
}

/// [`Interleave`] for a grid: its walk type, and its single-ray trace of `ray` as an expression
/// of `grid`, `tris`, `ray` and `opts`.
macro_rules! interleave {
    ($grid:ty, $walk:ident, |$g:ident, $tris:ident, $ray:ident, $opts:ident| $trace:expr) => {
        impl Interleave for $grid {
            type Walk<'g> = $walk<'g>;
            fn walk<'g>(&'g self, search: &ClosestHit) -> Option<$walk<'g>> {
                $walk::new(self, search)
            }
            fn memory_bytes(&self) -> u64 {
                <$grid>::memory_bytes(self)
            }
            fn trace_one(&self, $tris: &[[Vec3; 3]], $ray: &Ray, $opts: TraceOptions) -> (Hit, RayStats) {
                let $g = self;
                $trace
            }
        }
    };
}
interleave!(FlatGrid, FlatWalk, |g, tris, ray, opts| trace_flat(g, tris, ray, opts));
interleave!(MacrocellGrid, MacrocellWalk, |g, tris, ray, opts| g.trace(tris, ray, opts));
interleave!(ProximityGrid, ProximityWalk, |g, tris, ray, opts| g.trace(tris, ray, opts));

/// Closest hits (or any hits) of a chunk of `rays` in `grid`, written to `hits`: interleaved
/// when it [`pays`], else ray by ray.
pub fn trace_chunk<G: Interleave>(
    grid: &G,
    tris: &[[Vec3; 3]],
    rays: &[Ray],
    hits: &mut [Hit],
    opts: TraceOptions,
) -> BatchStats {
    if pays(grid.memory_bytes() + size_of_val(tris) as u64, rays) {
        trace_grid_interleaved(grid, tris, rays, hits, opts)
    } else {
        trace_each(rays, hits, |r| grid.trace_one(tris, r, opts))
    }
}

/// Where a ray's walk stands between two turns.
#[derive(Clone, Copy, Debug)]
enum Stage {
    /// Walking: the next cells until an occupied one (empty cells cost a bit test).
    Walk,
    /// At occupied cell `cell` (its entry of `ref_start` asked for) left at `t_exit`.
    Offset { cell: UVec3, entry: usize, t_exit: f32 },
    /// Its references `start..end` asked for.
    Refs { start: usize, end: usize, t_exit: f32 },
    /// Its triangles asked for: test them.
    Test { start: usize, end: usize, t_exit: f32 },
}

/// A structure's walk to its next occupied cell of a flat grid (the flat grid's own cells, or a
/// macrocell grid's fine cells inside its occupied macrocells), paused there.
pub trait CellWalk {
    /// The flat grid whose cells the walk visits.
    fn cells(&self) -> &FlatGrid;
    /// The ray in that grid's space for its cells' slab checks ([`crate::cell_plane`]), as
    /// the single-ray walk checks them.
    fn cell_ray(&self) -> Option<&CellRay>;
    /// Walks on to the next occupied cell: the cell, its index and the `t` where the ray leaves
    /// it, or `None` when the walk ended or `search` is done in an empty cell. Every visited
    /// cell is counted in `cells`, as the single-ray walk counts it.
    fn next_occupied(&mut self, search: &ClosestHit, cells: &mut u32) -> Option<(UVec3, usize, f32)>;
}

/// The cells of `walk` in `grid` up to the next occupied one (see [`CellWalk::next_occupied`]).
#[inline(always)]
fn next_occupied_of(
    walk: &mut LinearWalk,
    grid: &FlatGrid,
    search: &ClosestHit,
    cells: &mut u32,
) -> Option<Option<(UVec3, usize, f32)>> {
    while let Some((cell, index, t_exit)) = walk.next_cell() {
        *cells += 1;
        if grid.is_occupied(index) {
            return Some(Some((cell, index, t_exit)));
        }
        if search.done_at(t_exit) {
            return Some(None);
        }
    }
    // The walk ended.
    None
}

/// The flat grid's walk ([`super::trace_flat`]'s).
#[derive(Debug)]
pub struct FlatWalk<'g> {
    grid: &'g FlatGrid,
    walk: LinearWalk,
    cell_ray: Option<CellRay>,
}

impl<'g> FlatWalk<'g> {
    /// The walk of `search`'s ray through `grid`, or `None` when the ray misses the grid.
    pub fn new(grid: &'g FlatGrid, search: &ClosestHit) -> Option<FlatWalk<'g>> {
        let gr = grid.geom.clip(&search.ray)?;
        Some(FlatWalk { grid, walk: AmanatidesWoo::new(&gr, grid.geom.res).linear(), cell_ray: grid.cell_ray(&gr) })
    }
}

impl CellWalk for FlatWalk<'_> {
    fn cells(&self) -> &FlatGrid {
        self.grid
    }

    fn cell_ray(&self) -> Option<&CellRay> {
        self.cell_ray.as_ref()
    }

    #[inline]
    fn next_occupied(&mut self, search: &ClosestHit, cells: &mut u32) -> Option<(UVec3, usize, f32)> {
        next_occupied_of(&mut self.walk, self.grid, search, cells).flatten()
    }
}

/// The macrocell grid's walk ([`MacrocellGrid::trace`]'s): the fine cells, with the empty
/// macrocells crossed as blocks ([`LinearWalk::cross_blocks`]).
#[derive(Debug)]
pub struct MacrocellWalk<'g> {
    grid: &'g MacrocellGrid,
    walk: LinearWalk,
    cell_ray: Option<CellRay>,
}

impl<'g> MacrocellWalk<'g> {
    /// The walk of `search`'s ray through `grid`, or `None` when the ray misses the grid.
    pub fn new(grid: &'g MacrocellGrid, search: &ClosestHit) -> Option<MacrocellWalk<'g>> {
        let fine_ray = grid.fine.geom.clip(&search.ray)?;
        Some(MacrocellWalk {
            grid,
            walk: AmanatidesWoo::new(&fine_ray, grid.fine.geom.res).linear(),
            cell_ray: grid.fine.cell_ray(&fine_ray),
        })
    }
}

impl CellWalk for MacrocellWalk<'_> {
    fn cells(&self) -> &FlatGrid {
        &self.grid.fine
    }

    fn cell_ray(&self) -> Option<&CellRay> {
        self.cell_ray.as_ref()
    }

    #[inline]
    fn next_occupied(&mut self, search: &ClosestHit, cells: &mut u32) -> Option<(UVec3, usize, f32)> {
        let (grid, log2) = (self.grid, self.grid.log2_edge());
        loop {
            // The single-ray walk's visit ([`MacrocellGrid::visit`]), counted alike.
            let (cell, addr) = self.walk.current()?;
            if !grid.fine.is_occupied(addr) && !grid.occupied(cell >> log2) {
                *cells += 1;
                if !self.walk.cross_blocks(log2, |m| !grid.occupied(m), cells) {
                    return None;
                }
                continue;
            }
            let (cell, addr, t_exit) = self.walk.next_cell()?;
            *cells += 1;
            if grid.fine.is_occupied(addr) {
                return Some((cell, addr, t_exit));
            }
            if search.done_at(t_exit) {
                return None;
            }
        }
    }
}

/// The proximity grid's walk ([`ProximityGrid::trace`]'s): the flat grid's, restarted beyond
/// each empty cube it jumps out of.
#[derive(Debug)]
pub struct ProximityWalk<'g> {
    grid: &'g ProximityGrid,
    /// The segment still to walk (its start moves with each jump).
    ray: GridRay,
    walk: LinearWalk,
}

impl<'g> ProximityWalk<'g> {
    /// The walk of `search`'s ray through `grid`, or `None` when the ray misses the grid.
    pub fn new(grid: &'g ProximityGrid, search: &ClosestHit) -> Option<ProximityWalk<'g>> {
        let ray = grid.grid.geom.clip(&search.ray)?;
        Some(ProximityWalk { grid, ray, walk: AmanatidesWoo::new(&ray, grid.grid.geom.res).linear() })
    }
}

impl CellWalk for ProximityWalk<'_> {
    fn cells(&self) -> &FlatGrid {
        &self.grid.grid
    }

    /// The proximity grid's cells are tested without slab checks, as its single-ray walk does.
    fn cell_ray(&self) -> Option<&CellRay> {
        None
    }

    #[inline]
    fn next_occupied(&mut self, search: &ClosestHit, cells: &mut u32) -> Option<(UVec3, usize, f32)> {
        loop {
            let (cell, idx, t_exit) = self.walk.next_cell()?;
            *cells += 1;
            match self.grid.jump(&self.ray, cell, idx) {
                Jump::Restart(t) => {
                    self.ray.t0 = t;
                    self.walk = AmanatidesWoo::new(&self.ray, self.grid.grid.geom.res).linear();
                }
                Jump::End => return None,
                Jump::Step { empty: true } => {
                    if search.done_at(t_exit) {
                        return None;
                    }
                }
                Jump::Step { empty: false } => return Some((cell, idx, t_exit)),
            }
        }
    }
}

/// One ray in flight.
struct Slot<'a, W> {
    /// Its index in the batch.
    ray: usize,
    search: ClosestHit<'a>,
    walk: W,
    cells: u32,
    stage: Stage,
}

impl<W: CellWalk> Slot<'_, W> {
    /// One turn: the ray's next stage. Its result when the search is done.
    #[inline]
    fn turn(&mut self) -> Option<(Hit, RayStats)> {
        match self.stage {
            Stage::Walk => {
                let Some((cell, index, t_exit)) = self.walk.next_occupied(&self.search, &mut self.cells) else {
                    return Some(self.finish());
                };
                let grid = self.walk.cells();
                let entry = grid.rank(index);
                prefetch(&grid.ref_start, entry);
                if self.walk.cell_ray().is_some() {
                    prefetch(&grid.planes, entry);
                }
                self.stage = Stage::Offset { cell, entry, t_exit };
            }
            Stage::Offset { cell, entry, t_exit } => {
                let grid = self.walk.cells();
                // A cell whose slab the segment misses is passed as an empty one, as the
                // single-ray walk passes it.
                if grid.slab_misses(self.walk.cell_ray().map(|r| (r, cell)), entry, t_exit) {
                    if self.search.done_at(t_exit) {
                        return Some(self.finish());
                    }
                    self.stage = Stage::Walk;
                    return None;
                }
                let (start, end) = (grid.ref_start[entry] as usize, grid.ref_start[entry + 1] as usize);
                prefetch(&grid.refs, start);
                self.stage = Stage::Refs { start, end, t_exit };
            }
            Stage::Refs { start, end, t_exit } => {
                for &tri in &self.walk.cells().refs[start..end] {
                    prefetch(self.search.triangles(), tri as usize);
                }
                self.stage = Stage::Test { start, end, t_exit };
            }
            Stage::Test { start, end, t_exit } => {
                if self.search.test_cell(&self.walk.cells().refs[start..end], t_exit) {
                    return Some(self.finish());
                }
                self.stage = Stage::Walk;
            }
        }
        None
    }

    fn finish(&mut self) -> (Hit, RayStats) {
        self.search.visit_cells(self.cells);
        self.search.result()
    }
}

/// Closest hits (or any hits, by `opts.query`) of `rays` over `tris`, written to `hits` (as
/// long as `rays`), [`SLOTS`] rays walking at once, each along the walk `walk` gives its search
/// (`None`: the ray misses the structure); the rays' stats summed.
pub fn trace_interleaved<W: CellWalk>(
    tris: &[[Vec3; 3]],
    rays: &[Ray],
    hits: &mut [Hit],
    opts: TraceOptions,
    walk: impl Fn(&ClosestHit) -> Option<W>,
) -> BatchStats {
    assert_eq!(rays.len(), hits.len(), "one hit per ray");
    let mut stats = BatchStats::default();
    let mut slots: [Option<Slot<W>>; SLOTS] = std::array::from_fn(|_| None);
    let mut next = 0;
    loop {
        let mut walking = false;
        for slot in &mut slots {
            // An empty slot takes the next rays until one has cells to walk.
            while slot.is_none() && next < rays.len() {
                let search = ClosestHit::start(tris, &rays[next], opts);
                match search.map(|s| (walk(&s), s)) {
                    Some((Some(w), search)) => {
                        *slot = Some(Slot { ray: next, search, walk: w, cells: 0, stage: Stage::Walk });
                    }
                    unwalked => {
                        let (hit, s) = unwalked.map_or((Hit::MISS, RayStats::default()), |(_, s)| s.result());
                        hits[next] = hit;
                        stats.add(s, hit.is_hit());
                    }
                }
                next += 1;
            }
            let Some(s) = slot else { continue };
            walking = true;
            if let Some((hit, rs)) = s.turn() {
                hits[s.ray] = hit;
                stats.add(rs, hit.is_hit());
                *slot = None;
            }
        }
        if !walking {
            return stats;
        }
    }
}

/// Closest hits (or any hits, by `opts.query`) of `rays` in `grid` over `tris`, written to
/// `hits` (as long as `rays`), [`SLOTS`] rays walking at once; the rays' stats summed. The
/// hits and stats of the grid's single-ray trace ray by ray (Amanatides–Woo).
pub fn trace_grid_interleaved<G: Interleave>(
    grid: &G,
    tris: &[[Vec3; 3]],
    rays: &[Ray],
    hits: &mut [Hit],
    opts: TraceOptions,
) -> BatchStats {
    trace_interleaved(tris, rays, hits, opts, |search| grid.walk(search))
}
