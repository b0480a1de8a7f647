//! Closest-hit tracing through a flat grid with any traversal, optional mailboxing, and
//! per-ray stats.
//!
//! The loop visits cells in order; every triangle of a cell is tested (unless mailboxed) and
//! the best hit so far is kept by (t, triangle index). Traversal stops at the first cell whose
//! exit `t` is strictly greater than the best hit's `t`: the hit is accepted only once its `t`
//! lies within a visited cell's range. A hit found beyond the current cell stays a candidate
//! instead of being thrown away (so the mailbox can never hide it); a triangle with an equal or
//! smaller `t` must overlap a cell up to the current one, thanks to the conservative insertion
//! margin (see [`crate::geometry`]), so it has been tested by then. The result is bit-identical
//! to [`crate::brute::trace`].

use glam::Vec3;
use gridrt_scene::{Hit, Ray};

use crate::flat::FlatGrid;
use crate::mailbox::Mailbox;
use crate::stats::{BatchStats, RayStats};
use crate::traversal::amanatides_woo::AmanatidesWoo;
use crate::traversal::bresenham::Bresenham;
use crate::traversal::cleary_wyvill::ClearyWyvill;
use crate::traversal::liu::Liu;
use crate::traversal::{CellStep, Traversal};
use crate::triangle::{PreparedRay, closer, intersect};

/// Per-trace settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceOptions {
    pub traversal: Traversal,
    pub mailbox: bool,
}

/// Closest hit of `ray` in `grid` over `tris` (the triangles the grid was built from).
pub fn trace_flat(grid: &FlatGrid, tris: &[[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> (Hit, RayStats) {
    let Some(pr) = PreparedRay::new(ray) else {
        return (Hit::MISS, RayStats::default());
    };
    let Some(gr) = grid.geom.clip(&pr) else {
        return (Hit::MISS, RayStats::default());
    };
    let res = grid.geom.res;
    match opts.traversal {
        Traversal::AmanatidesWoo => closest_hit(AmanatidesWoo::new(&gr, res), grid, tris, &pr, opts.mailbox),
        Traversal::ClearyWyvill => closest_hit(ClearyWyvill::new(&gr, res), grid, tris, &pr, opts.mailbox),
        Traversal::Liu => closest_hit(Liu::new(&gr, res), grid, tris, &pr, opts.mailbox),
        Traversal::Bresenham => closest_hit(Bresenham::new(&gr, res), grid, tris, &pr, opts.mailbox),
    }
}

#[inline]
fn closest_hit(
    walker: impl Iterator<Item = CellStep>,
    grid: &FlatGrid,
    tris: &[[Vec3; 3]],
    pr: &PreparedRay,
    mailbox: bool,
) -> (Hit, RayStats) {
    let mut best = Hit::MISS;
    let mut stats = RayStats::default();
    let mut mb = Mailbox::default();
    for step in walker {
        stats.cells += 1;
        test_refs(
            grid.cell(grid.geom.cell_index(step.cell)),
            tris,
            pr,
            &mut best,
            &mut stats,
            mailbox.then_some(&mut mb),
        );
        if best.t < step.t_exit {
            break;
        }
    }
    (best, stats)
}

/// Tests the triangles `refs` of one cell (skipping mailboxed ones), keeping the closest hit
/// by (t, index) in `best` and counting tests: the inner loop of every structure's traversal.
#[inline]
pub fn test_refs(
    refs: &[u32],
    tris: &[[Vec3; 3]],
    pr: &PreparedRay,
    best: &mut Hit,
    stats: &mut RayStats,
    mut mailbox: Option<&mut Mailbox>,
) {
    for &tri in refs {
        if let Some(mb) = mailbox.as_deref_mut()
            && mb.check_and_insert(tri)
        {
            continue;
        }
        stats.tests += 1;
        if let Some(h) = intersect(pr, &tris[tri as usize])
            && closer(h.t, tri, best.t, best.triangle)
        {
            *best = Hit { t: h.t, triangle: tri, u: h.u, v: h.v };
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
