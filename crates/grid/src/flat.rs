//! The flat uniform grid in the compact layout of Lagae & Dutré (2008): `cell_start` (M + 1
//! offsets) and `refs` (triangle indices), cell `c` owning `refs[cell_start[c]..cell_start[c+1]]`.
//!
//! Built sort-last in linear time (survey Algorithm 1): count the references per cell, prefix
//! sum, scatter. References in a cell are in increasing triangle order. The parallel build
//! counts and scatters with atomics, then sorts each cell's references, so that its output is
//! bit-identical to the serial build's.

// std::time::Instant panics on wasm32-unknown-unknown; web-time is std's Instant elsewhere.
use web_time::Instant;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::BuildError;
use crate::geometry::{GridGeometry, INSERT_MARGIN_CELLS};
use crate::insert::{InsertMode, bucket};

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
        self.0.push((name.to_string(), start.elapsed().as_secs_f64() * 1e3));
        r
    }
    pub fn total(&self) -> f64 {
        self.0.iter().map(|p| p.1).sum()
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlatGrid {
    pub geom: GridGeometry,
    pub cell_start: Vec<u32>,
    pub refs: Vec<u32>,
}

/// Size figures of a built grid (`gridrt build`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FlatGridStats {
    pub resolution: [u32; 3],
    pub cells: u64,
    pub refs: u64,
    pub empty_cells: u64,
    pub empty_percent: f64,
    pub max_refs_per_cell: u32,
    pub refs_per_triangle: f64,
    pub memory_bytes: u64,
}

impl FlatGrid {
    /// Triangle indices in cell `index`.
    #[inline]
    pub fn cell(&self, index: usize) -> &[u32] {
        &self.refs[self.cell_start[index] as usize..self.cell_start[index + 1] as usize]
    }

    pub fn memory_bytes(&self) -> u64 {
        (self.cell_start.len() + self.refs.len()) as u64 * 4
    }

    pub fn stats(&self, triangles: usize) -> FlatGridStats {
        let cells = self.geom.cell_count();
        let mut empty = 0;
        let mut max = 0;
        for w in self.cell_start.windows(2) {
            let n = w[1] - w[0];
            empty += (n == 0) as u64;
            max = max.max(n);
        }
        FlatGridStats {
            resolution: self.geom.res.to_array(),
            cells,
            refs: self.refs.len() as u64,
            empty_cells: empty,
            empty_percent: 100.0 * empty as f64 / cells as f64,
            max_refs_per_cell: max,
            refs_per_triangle: self.refs.len() as f64 / triangles.max(1) as f64,
            memory_bytes: self.memory_bytes(),
        }
    }

    /// Builds the grid `geom` over `tris`. Timings are appended to `times`.
    pub fn build(
        tris: &[[Vec3; 3]],
        geom: GridGeometry,
        opts: BuildOptions,
        times: &mut PhaseTimes,
    ) -> Result<FlatGrid, BuildError> {
        if tris.len() as u64 >= u32::MAX as u64 {
            return Err(BuildError::TooManyTriangles(tris.len() as u64));
        }
        #[cfg(feature = "parallel")]
        if opts.parallel {
            return parallel::build(tris, geom, opts.insert, times);
        }
        build_serial(tris, geom, opts.insert, times)
    }
}

/// Exclusive prefix sum of per-cell counts into `cell_start` (M + 1 entries).
pub(crate) fn prefix_sum(counts: impl Iterator<Item = u32>, cells: usize) -> Result<Vec<u32>, BuildError> {
    let mut start = Vec::with_capacity(cells + 1);
    let mut acc = 0u64;
    for c in counts {
        start.push(acc as u32);
        acc += c as u64;
        if acc > MAX_REFS {
            return Err(BuildError::TooManyReferences { refs: acc, limit: MAX_REFS });
        }
    }
    start.push(acc as u32);
    Ok(start)
}

fn build_serial(
    tris: &[[Vec3; 3]],
    geom: GridGeometry,
    mode: InsertMode,
    times: &mut PhaseTimes,
) -> Result<FlatGrid, BuildError> {
    let (cell_start, refs) = bucket(tris, None, &geom, mode, INSERT_MARGIN_CELLS, Some(times))?;
    Ok(FlatGrid { geom, cell_start, refs })
}

#[cfg(feature = "parallel")]
mod parallel {
    use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

    use rayon::prelude::*;

    use super::*;
    use crate::insert::{for_each_cell, prepare};

    pub(super) fn build(
        tris: &[[Vec3; 3]],
        geom: GridGeometry,
        mode: InsertMode,
        times: &mut PhaseTimes,
    ) -> Result<FlatGrid, BuildError> {
        let cells = geom.cell_count() as usize;
        let counts: Vec<AtomicU32> = times.record("count", || {
            let counts: Vec<AtomicU32> = (0..cells).into_par_iter().map(|_| AtomicU32::new(0)).collect();
            tris.par_iter().for_each(|tri| {
                for_each_cell(&geom, &prepare(&geom, tri, INSERT_MARGIN_CELLS), mode, |c| {
                    counts[c].fetch_add(1, Relaxed);
                });
            });
            counts
        });
        let cell_start = times.record("scan", || prefix_sum(counts.iter().map(|c| c.load(Relaxed)), cells))?;
        let refs = times.record("scatter", || {
            counts.par_iter().zip(&cell_start[..cells]).for_each(|(c, s)| c.store(*s, Relaxed));
            let refs: Vec<AtomicU32> = (0..cell_start[cells]).into_par_iter().map(|_| AtomicU32::new(0)).collect();
            tris.par_iter().enumerate().for_each(|(i, tri)| {
                for_each_cell(&geom, &prepare(&geom, tri, INSERT_MARGIN_CELLS), mode, |c| {
                    let slot = counts[c].fetch_add(1, Relaxed);
                    refs[slot as usize].store(i as u32, Relaxed);
                });
            });
            refs.into_par_iter().map(AtomicU32::into_inner).collect::<Vec<u32>>()
        });
        // Scatter order within a cell depends on thread timing; sorting restores the serial
        // (increasing triangle) order. Work is split into runs of whole cells.
        let refs = times.record("sort", || {
            let mut refs = refs;
            let target = (refs.len() / (rayon::current_num_threads() * 16)).max(4096);
            let mut pieces: Vec<(&mut [u32], &[u32])> = Vec::new();
            let mut rest: &mut [u32] = &mut refs;
            let mut cell = 0;
            while cell < cells {
                let first = cell;
                let base = cell_start[first];
                while cell < cells
                    && (cell_start[cell + 1] - base) as usize <= target.max((cell_start[first + 1] - base) as usize)
                {
                    cell += 1;
                }
                let len = (cell_start[cell] - base) as usize;
                let (piece, tail) = std::mem::take(&mut rest).split_at_mut(len);
                rest = tail;
                pieces.push((piece, &cell_start[first..=cell]));
            }
            pieces.into_par_iter().for_each(|(piece, starts)| {
                let base = starts[0];
                for w in starts.windows(2) {
                    piece[(w[0] - base) as usize..(w[1] - base) as usize].sort_unstable();
                }
            });
            refs
        });
        Ok(FlatGrid { geom, cell_start, refs })
    }
}
