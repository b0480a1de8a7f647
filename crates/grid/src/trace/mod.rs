//! Tracing: the closest-hit rule ([`closest_hit`], shared by every structure), the flat grid's
//! walk, batches of rays on all threads, and [`interleaved`] walks for incoherent batches.

pub mod closest_hit;
pub mod interleaved;

use glam::Vec3;
use gridrt_scene::{Hit, Ray};

use crate::flat::FlatGrid;
use crate::stats::{BatchStats, RayStats};
use crate::traversal::{Traversal, walk_counted};
pub use closest_hit::Query;
use closest_hit::closest_hit;

/// Per-trace settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceOptions {
    pub traversal: Traversal,
    pub mailbox: bool,
    /// Closest hit, or any hit (occlusion).
    pub query: Query,
    /// Batches of incoherent rays on a large flat, macrocell or proximity grid walk interleaved
    /// ([`interleaved`]; the same hits and stats). Off: every ray walks alone, as the other
    /// structures' rays do (for comparing walks one to one).
    pub interleave: bool,
}

impl Default for TraceOptions {
    /// Amanatides–Woo, no mailbox, closest hits, interleaving where it pays.
    fn default() -> TraceOptions {
        TraceOptions { traversal: Traversal::AmanatidesWoo, mailbox: false, query: Query::Closest, interleave: true }
    }
}

impl TraceOptions {
    /// Amanatides–Woo with the mailbox, closest hits: what the benchmarks, probes and renders
    /// trace with unless told otherwise.
    pub const MAILBOX: TraceOptions =
        TraceOptions { traversal: Traversal::AmanatidesWoo, mailbox: true, query: Query::Closest, interleave: true };

    /// These options for an occlusion query ([`Query::Any`]).
    pub fn occlusion(self) -> TraceOptions {
        TraceOptions { query: Query::Any, ..self }
    }
}

/// Closest hit (or any hit, by `opts.query`) of `ray` in `grid` over `tris` (the triangles the
/// grid was built from).
pub fn trace_flat(grid: &FlatGrid, tris: &[[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> (Hit, RayStats) {
    closest_hit(tris, ray, opts, |search| {
        let Some(gr) = grid.geom.clip(&search.ray) else { return };
        // The slab check's segment starts at the cell's entry as Amanatides–Woo computes it,
        // which is the walk's own only for that walker (Liu's and Cleary–Wyvill's cells can be
        // entered slightly earlier): the other walkers test every occupied cell.
        let cr = if opts.traversal == Traversal::AmanatidesWoo { grid.cell_ray(&gr) } else { None };
        let (_, cells) = walk_counted(opts.traversal, &gr, grid.geom.res, |c, index, t_exit| {
            grid.visit(search, cr.as_ref().map(|r| (r, c)), index, t_exit)
        });
        search.visit_cells(cells);
    })
}

/// Traces a batch (in parallel with the `parallel` feature and `parallel = true`).
pub fn trace_batch(
    rays: &[Ray],
    parallel: bool,
    one: impl Fn(&Ray) -> (Hit, RayStats) + Sync,
) -> (Vec<Hit>, BatchStats) {
    trace_chunks(rays, parallel, |chunk, out| trace_each(chunk, out, &one))
}

/// Traces `rays` one after another with `one`, writing `hits` in place; their stats summed.
#[inline]
pub fn trace_each(rays: &[Ray], hits: &mut [Hit], one: impl Fn(&Ray) -> (Hit, RayStats)) -> BatchStats {
    let mut stats = BatchStats::default();
    for (r, h) in rays.iter().zip(hits) {
        let (hit, s) = one(r);
        stats.add(s, hit.is_hit());
        *h = hit;
    }
    stats
}

/// Traces a batch chunk by chunk: `run(rays, hits)` writes the hits of a chunk's rays in place
/// and returns their stats (in parallel with the `parallel` feature and `parallel = true`).
pub fn trace_chunks(
    rays: &[Ray],
    parallel: bool,
    run: impl Fn(&[Ray], &mut [Hit]) -> BatchStats + Sync,
) -> (Vec<Hit>, BatchStats) {
    let mut hits = vec![Hit::MISS; rays.len()];
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        let stats = rays
            .par_chunks(1024)
            .zip(hits.par_chunks_mut(1024))
            .map(|(c, o)| run(c, o))
            .reduce(BatchStats::default, BatchStats::merge);
        return (hits, stats);
    }
    let _ = parallel;
    let stats = run(rays, &mut hits);
    (hits, stats)
}
