//! Tracing: the closest-hit rule ([`closest_hit`], shared by every structure), the flat grid's
//! walk, and batches of rays on all threads.

pub mod closest_hit;

use glam::Vec3;
use gridrt_scene::{Hit, Ray};

use crate::flat::FlatGrid;
use crate::stats::{BatchStats, RayStats};
use crate::traversal::amanatides_woo::AmanatidesWoo;
use crate::traversal::bresenham::Bresenham;
use crate::traversal::cleary_wyvill::ClearyWyvill;
use crate::traversal::liu::Liu;
use crate::traversal::{CellStep, Traversal};
use closest_hit::{ClosestHit, closest_hit};

/// Per-trace settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceOptions {
    pub traversal: Traversal,
    pub mailbox: bool,
}

/// Closest hit of `ray` in `grid` over `tris` (the triangles the grid was built from). Each
/// walker is its own type here (not [`crate::traversal::Walker`]), so the loop is compiled once
/// per traversal.
pub fn trace_flat(grid: &FlatGrid, tris: &[[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> (Hit, RayStats) {
    closest_hit(tris, ray, opts.mailbox, |search| {
        let Some(gr) = grid.geom.clip(&search.ray) else { return };
        let res = grid.geom.res;
        match opts.traversal {
            Traversal::AmanatidesWoo => walk_flat(AmanatidesWoo::new(&gr, res), grid, search),
            Traversal::ClearyWyvill => walk_flat(ClearyWyvill::new(&gr, res), grid, search),
            Traversal::Liu => walk_flat(Liu::new(&gr, res), grid, search),
            Traversal::Bresenham => walk_flat(Bresenham::new(&gr, res), grid, search),
        }
    })
}

#[inline]
fn walk_flat(walker: impl Iterator<Item = CellStep>, grid: &FlatGrid, search: &mut ClosestHit) {
    for step in walker {
        search.visit_cell();
        if search.test_cell(grid.cell(grid.geom.cell_index(step.cell)), step.t_exit) {
            return;
        }
    }
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
