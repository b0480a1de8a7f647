//! Tracing: the closest-hit rule ([`closest_hit`], shared by every structure), the flat grid's
//! walk, and batches of rays on all threads.

pub mod closest_hit;

use glam::Vec3;
use gridrt_scene::{Hit, Ray};

use crate::flat::FlatGrid;
use crate::stats::{BatchStats, RayStats};
use crate::traversal::{Traversal, walk};
pub use closest_hit::Query;
use closest_hit::closest_hit;

/// Per-trace settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceOptions {
    pub traversal: Traversal,
    pub mailbox: bool,
    /// Closest hit, or any hit (occlusion).
    pub query: Query,
}

impl TraceOptions {
    /// Amanatides–Woo with the mailbox, closest hits: what the benchmarks, probes and renders
    /// trace with unless told otherwise.
    pub const MAILBOX: TraceOptions =
        TraceOptions { traversal: Traversal::AmanatidesWoo, mailbox: true, query: Query::Closest };

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
        walk(opts.traversal, &gr, grid.geom.res, |_, index, t_exit| grid.visit(search, index, t_exit));
    })
}

/// Traces a batch (in parallel with the `parallel` feature and `parallel = true`).
pub fn trace_batch(
    rays: &[Ray],
    parallel: bool,
    one: impl Fn(&Ray) -> (Hit, RayStats) + Sync,
) -> (Vec<Hit>, BatchStats) {
    let run = |chunk: &[Ray]| {
        let mut stats = BatchStats::default();
        let hits: Vec<Hit> = chunk
            .iter()
            .map(|r| {
                let (h, s) = one(r);
                stats.add(s, h.is_hit());
                h
            })
            .collect();
        (hits, stats)
    };
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        let parts: Vec<(Vec<Hit>, BatchStats)> = rays.par_chunks(1024).map(run).collect();
        let mut hits = Vec::with_capacity(rays.len());
        let mut stats = BatchStats::default();
        for (h, s) in parts {
            hits.extend(h);
            stats = stats.merge(s);
        }
        return (hits, stats);
    }
    let _ = parallel;
    run(rays)
}
