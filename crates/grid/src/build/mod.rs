//! What every structure's build shares: options, phase timings, the reference and cell limits,
//! fallible allocation, and the bucketing of triangles into a grid's cells (count → prefix sum
//! → scatter, survey Algorithm 1), serial in [`bucket`] and parallel in [`parallel`].

pub mod bucket;
#[cfg(feature = "parallel")]
pub mod parallel;

// std::time::Instant panics on wasm32-unknown-unknown; web-time is std's Instant elsewhere.
use web_time::Instant;

use serde::{Deserialize, Serialize};

use crate::BuildError;
use crate::insert::InsertMode;

/// Largest number of references a grid may hold (u32 offsets; keeps memory bounded).
pub const MAX_REFS: u64 = 1 << 31;

/// How a grid is built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct BuildOptions {
    pub insert: InsertMode,
    /// Use all threads (rayon); the result is identical to the serial build.
    pub parallel: bool,
}

/// Milliseconds per build phase, in execution order.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PhaseTimes(pub Vec<(String, f64)>);

impl PhaseTimes {
    pub fn record<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let r = f();
        self.record_since(name, start);
        r
    }
    /// Records the phase `name` as started at `start` and ended now (added to the last phase
    /// when it has the same name).
    pub fn record_since(&mut self, name: &str, start: Instant) {
        let ms = start.elapsed().as_secs_f64() * 1e3;
        match self.0.last_mut() {
            Some((last, t)) if last == name => *t += ms,
            _ => self.0.push((name.to_string(), ms)),
        }
    }
    pub fn total(&self) -> f64 {
        self.0.iter().map(|p| p.1).sum()
    }
}

/// The arrays a flat build can take over from the one before it, for a grid rebuilt every frame:
/// handed back with [`BuildScratch::recycle`], the previous grid's arrays.
/// Their memory is already mapped, so a rebuild does not pay its page faults again (about 2 µs
/// per 4 KiB page on a VM; a 1M-triangle scene's build touches ~100 MB). Used by the parallel
/// build; the result is the same as a build from nothing.
#[derive(Debug, Default)]
pub struct BuildScratch {
    pub(crate) refs: Vec<u32>,
    pub(crate) occupied: Vec<crate::flat::OccupancyWord>,
    pub(crate) ref_start: Vec<u32>,
}

impl BuildScratch {
    /// Takes back the arrays of a grid that is no longer needed (the flat grid of a flat,
    /// macrocell or proximity grid; others are dropped).
    pub fn recycle(&mut self, grid: crate::AnyGrid) {
        let Some(fine) = grid.into_flat() else { return };
        self.refs = fine.refs;
        self.occupied = fine.occupied;
        self.ref_start = fine.ref_start;
    }
}

/// Runs `f` on a thread of rayon's pool (at once when called from one): a build's parallel
/// phases then share their work with the other threads by work stealing, where each phase
/// started from outside the pool waits for a thread to take it up and to wake the caller (a
/// build has a dozen phases; the hand-overs were a few percent of a 50k-triangle build).
pub fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    #[cfg(feature = "parallel")]
    if rayon::current_thread_index().is_none() {
        return rayon::scope(|_| f());
    }
    f()
}

/// `v` holding `n` default values, written on all threads into the memory it already has
/// (more only when it is too small, see [`reserve_for_rebuild`]), or
/// [`BuildError::OutOfMemory`].
#[cfg(feature = "parallel")]
pub fn refill_par<T: Copy + Default + Send + Sync>(
    v: &mut Vec<T>,
    n: usize,
    what: &'static str,
) -> Result<(), BuildError> {
    use rayon::prelude::*;
    v.clear();
    reserve_for_rebuild(v, n, what)?;
    // Below 256 KiB the threads' hand-over costs more than the writes.
    if n * size_of::<T>() < 1 << 18 {
        v.resize(n, T::default());
    } else {
        v.par_extend(rayon::iter::repeat_n(T::default(), n));
    }
    Ok(())
}

/// `v` of length `n` for a caller that overwrites every entry: a previous build's array is cut
/// to length, or lengthened within its capacity, writing only the entries it did not have (a
/// rebuild every frame skips a pass over its references); else [`refill_par`].
#[cfg(feature = "parallel")]
pub fn resize_for_overwrite<T: Copy + Default + Send + Sync>(
    v: &mut Vec<T>,
    n: usize,
    what: &'static str,
) -> Result<(), BuildError> {
    if v.len() >= n {
        v.truncate(n);
        return Ok(());
    }
    if v.capacity() >= n {
        v.resize(n, T::default());
        return Ok(());
    }
    refill_par(v, n, what)
}

/// Makes room for `n` entries in the emptied `v`. A fresh array gets exactly `n`; a previous
/// build's array that is too small is replaced, not grown (growing copies its old contents,
/// which the caller overwrites anyway), by one with an eighth more room: a scene rebuilt every
/// frame whose reference count creeps up then does not get a new array, and its page faults,
/// every frame.
#[cfg(feature = "parallel")]
fn reserve_for_rebuild<T>(v: &mut Vec<T>, n: usize, what: &'static str) -> Result<(), BuildError> {
    debug_assert!(v.is_empty());
    if v.capacity() >= n {
        return Ok(());
    }
    let room = if v.capacity() == 0 { n } else { n.saturating_add(n / 8) };
    let mut fresh = Vec::new();
    fresh
        .try_reserve_exact(room)
        .or_else(|_| fresh.try_reserve_exact(n))
        .map_err(|_| BuildError::OutOfMemory { what, bytes: (n as u64).saturating_mul(size_of::<T>() as u64) })?;
    advise_huge_pages(&fresh);
    *v = fresh;
    Ok(())
}

/// Arrays from this size up ask for transparent huge pages.
#[cfg(target_os = "linux")]
const HUGE_PAGE_ARRAY_BYTES: usize = 4 << 20;

/// Asks the kernel to back `v`'s allocation with 2 MiB pages before it is first written (Linux,
/// where transparent huge pages are often in "madvise" mode): a fresh array of tens of MiB
/// otherwise takes a page fault every 4 KiB, which cost about a third of a one-shot build of
/// millions of triangles. Advice only: nothing changes where it is ignored.
fn advise_huge_pages<T>(v: &Vec<T>) {
    #[cfg(target_os = "linux")]
    {
        let bytes = v.capacity() * size_of::<T>();
        if bytes < HUGE_PAGE_ARRAY_BYTES {
            return;
        }
        const PAGE: usize = 4096;
        let start = v.as_ptr() as usize;
        let first = start.next_multiple_of(PAGE);
        let end = (start + bytes) & !(PAGE - 1);
        if end > first {
            // SAFETY: madvise only advises on pages of this allocation, which `v` owns; it
            // neither reads nor moves them.
            #[allow(unsafe_code)]
            unsafe {
                libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v;
}

/// A vector of `n` default values, or [`BuildError::OutOfMemory`] when the allocator refuses
/// (an address-space limit) instead of aborting the process.
pub fn zeroed<T: Copy + Default>(n: usize, what: &'static str) -> Result<Vec<T>, BuildError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| BuildError::OutOfMemory { what, bytes: (n as u64).saturating_mul(size_of::<T>() as u64) })?;
    advise_huge_pages(&v);
    v.resize(n, T::default());
    Ok(v)
}

/// Refuses a grid that would hold `refs` triangle references, more than [`MAX_REFS`].
pub fn check_refs(refs: u64) -> Result<(), BuildError> {
    if refs > MAX_REFS {
        return Err(BuildError::TooManyReferences { refs, limit: MAX_REFS });
    }
    Ok(())
}

/// Refuses a grid of resolution `res` with more than `limit` cells, before anything is allocated.
pub fn check_cells(res: [u32; 3], limit: u64) -> Result<(), BuildError> {
    let cells = res.iter().map(|&r| r as u64).product::<u64>();
    if cells > limit {
        return Err(BuildError::TooManyCells { cells, limit });
    }
    Ok(())
}

/// Splits `v` into consecutive mutable pieces of the given lengths.
pub(crate) fn split_lengths<T>(mut v: &mut [T], lengths: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut out = Vec::new();
    for len in lengths {
        let (a, b) = std::mem::take(&mut v).split_at_mut(len);
        out.push(a);
        v = b;
    }
    out
}
