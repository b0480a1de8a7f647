//! The closest-hit rule, written once for every structure (the WGSL twin is
//! `shaders/shared/closest_hit.wgsl`).
//!
//! A structure walks its cells in order of increasing `t` and hands each leaf's triangle
//! references to [`ClosestHit::test_cell`]. Every triangle of the cell is tested (unless
//! mailboxed) and the best hit so far is kept by (t, triangle index). The walk stops at the
//! first cell whose exit `t` is strictly greater than the best hit's `t`: the hit is accepted
//! only once its `t` lies within a visited cell's range. A hit found beyond the current cell
//! stays a candidate instead of being thrown away (so the mailbox can never hide it); a
//! triangle with an equal or smaller `t` must overlap a cell up to the current one, thanks to
//! the conservative insertion margin (see [`crate::geometry`]), so it has been tested by then.
//! The result is bit-identical to [`crate::brute::trace`].
//!
//! An occlusion query ([`Query::Any`], shadow rays) stops at the first hit found anywhere on the
//! ray's segment instead: which triangle that is depends on the structure, whether there is one
//! does not (it is the closest query's `is_hit`).

use glam::Vec3;
use gridrt_scene::{Hit, Ray};
use serde::{Deserialize, Serialize};

use crate::mailbox::Mailbox;
use crate::ray::PreparedRay;
use crate::stats::RayStats;
use crate::trace::TraceOptions;
use crate::triangle::{LANES, intersect, intersect_prefiltered, keep_closer, may_hit8};

/// What a search looks for ([`TraceOptions::query`]; the WGSL twin is `params.query`, `QUERY_*`
/// in shaders/shared/types.wgsl). Shadow rays are [`Query::Any`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Query {
    /// The closest hit by (t, triangle index): bit-identical across structures.
    #[default]
    Closest,
    /// Any hit on the ray's segment (occlusion, as for shadow rays): the search ends at the
    /// first hit found. Only whether the ray hits is defined; it equals the closest query's.
    Any,
}

/// One ray's search: the best hit so far, its stats and its mailbox.
#[derive(Debug)]
pub struct ClosestHit<'a> {
    tris: &'a [[Vec3; 3]],
    /// The ray, prepared for the watertight triangle test.
    pub ray: PreparedRay,
    best: Hit,
    stats: RayStats,
    mailbox: Option<Mailbox>,
    /// [`Query::Any`]: done at the first hit.
    any: bool,
}

impl<'a> ClosestHit<'a> {
    /// Counts one visited cell (a leaf, an internal cell or a skipped block).
    #[inline]
    pub fn visit_cell(&mut self) {
        self.stats.cells += 1;
    }

    /// Counts `n` visited cells (a walk that kept its own count).
    #[inline]
    pub fn visit_cells(&mut self, n: u32) {
        self.stats.cells += n;
    }

    /// Tests the triangles `refs` of a leaf the ray leaves at `t_exit` (skipping mailboxed
    /// ones), keeping the closest hit by (t, index). True when the search is done: the best hit
    /// lies before `t_exit`, so no later cell can hold a closer one (an occlusion query: as soon
    /// as there is a hit).
    #[inline]
    pub fn test_cell(&mut self, refs: &[u32], t_exit: f32) -> bool {
        // The triangles' loads start together, not one test after another: random rays miss
        // the cache on most of them.
        for &tri in refs {
            prefetch(self.tris, tri as usize);
        }
        // The triangles not mailboxed go through the f32 pre-filter eight at a time; only those
        // it cannot reject take the exact test, in the order of `refs`.
        let mut batch = [0u32; LANES];
        let mut n = 0;
        for &tri in refs {
            if let Some(mb) = self.mailbox.as_mut()
                && mb.check_and_insert(tri)
            {
                continue;
            }
            batch[n] = tri;
            n += 1;
            if n == LANES {
                if self.test_batch(&batch) {
                    return true;
                }
                n = 0;
            }
        }
        if n > 0 && self.test_batch(&batch[..n]) {
            return true;
        }
        self.done_at(t_exit)
    }

    /// Tests the triangles `ids` (at most [`LANES`]); true when an occlusion query is done.
    #[inline]
    fn test_batch(&mut self, ids: &[u32]) -> bool {
        self.stats.tests += ids.len() as u32;
        // One or two triangles are not worth the lanes: the exact test starts with the same
        // pre-filter.
        if ids.len() < 3 {
            self.test_exact::<true>(ids, (1u32 << ids.len()) - 1)
        } else {
            self.test_exact::<false>(ids, may_hit8(&self.ray, self.tris, ids))
        }
    }

    /// The exact tests of the triangles `ids[l]` for the bits `l` of `keep`, in order (with the
    /// f32 pre-filter first unless `keep` comes from it); true when an occlusion query is done.
    #[inline]
    fn test_exact<const PREFILTER: bool>(&mut self, ids: &[u32], mut keep: u32) -> bool {
        while keep != 0 {
            let tri = ids[keep.trailing_zeros() as usize];
            keep &= keep - 1;
            let t = &self.tris[tri as usize];
            let hit = if PREFILTER { intersect(&self.ray, t) } else { intersect_prefiltered(&self.ray, t) };
            if keep_closer(&mut self.best, hit, tri) && self.any {
                return true;
            }
        }
        false
    }

    /// True when the best hit lies before `t_exit` (the end of a cell or block just crossed, in
    /// the walk's units: [`PreparedRay::walk_t`]), compared in the ray's units as the hits are
    /// rounded ([`PreparedRay::ray_t`]): a later hit whose `t` rounds to the best one's (a tie
    /// the triangle index breaks) keeps the walk going.
    #[inline]
    pub fn done_at(&self, t_exit: f32) -> bool {
        self.best.t < self.ray.ray_t(t_exit)
    }
}

/// Asks the CPU to start loading element `i` of `items` into the cache (the line of its first
/// byte: a triangle's first corner, a cell's offset or reference). A hint only: it changes no
/// result, and elsewhere than on x86-64 it does nothing.
#[inline(always)]
pub(crate) fn prefetch<T>(items: &[T], i: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let p = items.as_ptr().wrapping_add(i).cast::<i8>();
        // SAFETY: a prefetch never faults and reads nothing the program sees, whatever the
        // address; SSE is part of the x86-64 baseline.
        #[allow(unsafe_code)]
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(p)
        };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (items, i);
}

/// The closest hit of `ray` among `tris` (the triangles the structure was built from), or any
/// hit for [`Query::Any`]: `walk` visits the structure's cells in order and returns when
/// [`ClosestHit::test_cell`] says the search is done or the cells run out.
#[inline]
pub fn closest_hit(
    tris: &[[Vec3; 3]],
    ray: &Ray,
    opts: TraceOptions,
    walk: impl FnOnce(&mut ClosestHit),
) -> (Hit, RayStats) {
    let Some(mut search) = ClosestHit::start(tris, ray, opts) else {
        return (Hit::MISS, RayStats::default());
    };
    walk(&mut search);
    search.result()
}

impl<'a> ClosestHit<'a> {
    /// The search of `ray` before any cell, or `None` for a ray no triangle can be hit by (a
    /// miss). [`closest_hit`] is `start`, the walk, then [`ClosestHit::result`].
    #[inline(always)]
    pub fn start(tris: &'a [[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> Option<ClosestHit<'a>> {
        Some(ClosestHit {
            tris,
            ray: PreparedRay::new(ray)?,
            best: Hit::MISS,
            stats: RayStats::default(),
            mailbox: opts.mailbox.then(Mailbox::default),
            any: opts.query == Query::Any,
        })
    }

    /// The best hit and the ray's stats.
    #[inline(always)]
    pub fn result(&self) -> (Hit, RayStats) {
        (self.best, self.stats)
    }

    /// The triangles the structure was built from.
    #[inline(always)]
    pub fn triangles(&self) -> &'a [[Vec3; 3]] {
        self.tris
    }
}
