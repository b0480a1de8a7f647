//! Interleaved walks: a batch's rays walk the flat grid [`SLOTS`] at a time, each advancing one
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

use glam::Vec3;
use gridrt_scene::{Hit, Ray};

use super::closest_hit::{ClosestHit, prefetch};
use super::{TraceOptions, trace_each, trace_flat};
use crate::flat::{FlatGrid, WORD_CELLS};
use crate::stats::{BatchStats, RayStats};
use crate::traversal::amanatides_woo::{AmanatidesWoo, LinearWalk};

/// Rays walking at once: enough turns between a prefetch and the load it serves to hide a miss
/// to the last-level cache.
pub const SLOTS: usize = 8;

/// Bytes of grid and triangles beyond which interleaving pays ([`trace_flat_chunk`]): below,
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

/// Closest hits (or any hits) of a chunk of `rays` in `grid`, written to `hits`: interleaved
/// when the grid and triangles outgrow the cache ([`INTERLEAVE_MIN_BYTES`]) and the rays are
/// [`incoherent`], else ray by ray. The same hits and stats either way.
pub fn trace_flat_chunk(
    grid: &FlatGrid,
    tris: &[[Vec3; 3]],
    rays: &[Ray],
    hits: &mut [Hit],
    opts: TraceOptions,
) -> BatchStats {
    let bytes = grid.memory_bytes() + size_of_val(tris) as u64;
    if bytes > INTERLEAVE_MIN_BYTES && incoherent(rays) {
        trace_flat_interleaved(grid, tris, rays, hits, opts)
    } else {
        trace_each(rays, hits, |r| trace_flat(grid, tris, r, opts))
    }
}

/// Where a ray's walk stands between two turns.
#[derive(Clone, Copy, Debug)]
enum Stage {
    /// Walking: the next cells until an occupied one (empty cells cost a bit test).
    Walk,
    /// At an occupied cell (its entry of `ref_start` asked for) left at `t_exit`.
    Offset { entry: usize, t_exit: f32 },
    /// Its references `start..end` asked for.
    Refs { start: usize, end: usize, t_exit: f32 },
    /// Its triangles asked for: test them.
    Test { start: usize, end: usize, t_exit: f32 },
}

/// One ray in flight.
struct Slot<'a> {
    /// Its index in the batch.
    ray: usize,
    search: ClosestHit<'a>,
    walk: LinearWalk,
    cells: u32,
    stage: Stage,
}

/// The search of `ray` (index `i`) ready to walk `grid`, or its result when there is nothing to
/// walk (a ray no triangle can be hit by, or one that misses the grid).
fn start<'a>(
    grid: &FlatGrid,
    tris: &'a [[Vec3; 3]],
    ray: &Ray,
    i: usize,
    opts: TraceOptions,
) -> Result<Slot<'a>, (Hit, RayStats)> {
    let Some(search) = ClosestHit::start(tris, ray, opts) else { return Err((Hit::MISS, RayStats::default())) };
    let Some(gr) = grid.geom.clip(&search.ray) else { return Err(search.result()) };
    let walk = AmanatidesWoo::new(&gr, grid.geom.res).linear();
    Ok(Slot { ray: i, search, walk, cells: 0, stage: Stage::Walk })
}

impl Slot<'_> {
    /// One turn: the ray's next stage. Its result when the search is done.
    #[inline]
    fn turn(&mut self, grid: &FlatGrid) -> Option<(Hit, RayStats)> {
        match self.stage {
            Stage::Walk => loop {
                let Some((_, index, t_exit)) = self.walk.next_cell() else { return Some(self.finish()) };
                self.cells += 1;
                if (grid.occupied[index / WORD_CELLS].bits >> (index % WORD_CELLS)) & 1 == 0 {
                    if self.search.done_at(t_exit) {
                        return Some(self.finish());
                    }
                    continue;
                }
                let entry = grid.rank(index);
                prefetch(&grid.ref_start, entry);
                self.stage = Stage::Offset { entry, t_exit };
                return None;
            },
            Stage::Offset { entry, t_exit } => {
                let (start, end) = (grid.ref_start[entry] as usize, grid.ref_start[entry + 1] as usize);
                prefetch(&grid.refs, start);
                self.stage = Stage::Refs { start, end, t_exit };
            }
            Stage::Refs { start, end, t_exit } => {
                for &tri in &grid.refs[start..end] {
                    prefetch(self.search.triangles(), tri as usize);
                }
                self.stage = Stage::Test { start, end, t_exit };
            }
            Stage::Test { start, end, t_exit } => {
                if self.search.test_cell(&grid.refs[start..end], t_exit) {
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

/// Closest hits (or any hits, by `opts.query`) of `rays` in `grid` over `tris`, written to
/// `hits` (as long as `rays`), [`SLOTS`] rays walking at once; the rays' stats summed. The
/// hits and stats of [`trace_flat`](super::trace_flat) ray by ray (Amanatides–Woo).
pub fn trace_flat_interleaved(
    grid: &FlatGrid,
    tris: &[[Vec3; 3]],
    rays: &[Ray],
    hits: &mut [Hit],
    opts: TraceOptions,
) -> BatchStats {
    assert_eq!(rays.len(), hits.len(), "one hit per ray");
    let mut stats = BatchStats::default();
    let mut slots: [Option<Slot>; SLOTS] = std::array::from_fn(|_| None);
    let mut next = 0;
    loop {
        let mut walking = false;
        for slot in &mut slots {
            // An empty slot takes the next rays until one has cells to walk.
            while slot.is_none() && next < rays.len() {
                match start(grid, tris, &rays[next], next, opts) {
                    Ok(s) => *slot = Some(s),
                    Err((hit, s)) => {
                        hits[next] = hit;
                        stats.add(s, hit.is_hit());
                    }
                }
                next += 1;
            }
            let Some(s) = slot else { continue };
            walking = true;
            if let Some((hit, rs)) = s.turn(grid) {
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
