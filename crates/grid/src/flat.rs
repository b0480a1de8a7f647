//! The flat uniform grid in the compact layout of Lagae & Dutré (2008) — triangle indices in
//! cell order (`refs`) and where each cell's run starts — with the offsets of empty cells
//! dropped: an occupancy bit per cell, and per 32 cells the rank that finds an occupied cell's
//! offset (`ref_start`). Most cells of a grid are empty, so a grid costs about a quarter of a
//! byte per cell, plus four bytes per occupied cell and per reference. The GPU holds the same
//! arrays (`shaders/shared/flat_grid.wgsl`).
//!
//! Built sort-last in linear time by [`crate::build::bucket`] (serial) or
//! [`crate::build::parallel`] (bit-identical): references in a cell are in increasing triangle
//! order.

use glam::{UVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::BuildError;
use crate::build::{BuildOptions, BuildScratch, PhaseTimes, bucket};
use crate::cell_plane::{CellPlane, CellRay};
use crate::geometry::{GridGeometry, INSERT_MARGIN_CELLS};
use crate::stats::StructureStats;
use crate::trace::closest_hit::ClosestHit;

/// 32 cells' occupancy (x fastest) and how many occupied cells precede them: the rank that
/// turns a cell index into its entry of [`FlatGrid::ref_start`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[repr(C)]
pub struct OccupancyWord {
    /// Bit j: cell 32k + j holds references.
    pub bits: u32,
    /// Occupied cells in words 0 … k − 1.
    pub rank: u32,
}

impl OccupancyWord {
    /// Sets each word's rank from the bits of the words before it; returns the occupied cells.
    pub(crate) fn rank_all(words: &mut [OccupancyWord]) -> u32 {
        let mut rank = 0u32;
        for w in words {
            w.rank = rank;
            rank += w.bits.count_ones();
        }
        rank
    }
}

/// Cells per [`OccupancyWord`].
pub const WORD_CELLS: usize = 32;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlatGrid {
    pub geom: GridGeometry,
    /// Per 32 cells, which hold references and the rank of the first (the survey's macrocell
    /// flags at cell granularity): a walk passes empty cells by a bit test, and an empty cell
    /// costs a quarter of a byte, not an offset (most cells of a grid are empty).
    pub occupied: Vec<OccupancyWord>,
    /// Per occupied cell, in cell order, the start of its references in `refs`; one more entry
    /// holds `refs.len()`.
    pub ref_start: Vec<u32>,
    pub refs: Vec<u32>,
    /// Per occupied cell, in the order of `ref_start`, the slab that holds its triangles
    /// ([`crate::cell_plane`]); empty when the grid has none.
    #[serde(default)]
    pub planes: Vec<CellPlane>,
}

impl FlatGrid {
    /// The grid of its arrays, as the parallel build writes them directly.
    #[cfg(feature = "parallel")]
    pub(crate) fn from_parts(
        geom: GridGeometry,
        occupied: Vec<OccupancyWord>,
        ref_start: Vec<u32>,
        refs: Vec<u32>,
    ) -> FlatGrid {
        FlatGrid { geom, occupied, ref_start, refs, planes: Vec::new() }
    }

    /// The grid of `geom` with cell `c` owning `refs[cell_start[c]..cell_start[c + 1]]` (the
    /// builds' table of M + 1 offsets), stored compactly: the empty cells' offsets are dropped.
    pub fn new(geom: GridGeometry, cell_start: Vec<u32>, refs: Vec<u32>) -> FlatGrid {
        let cells = cell_start.len().saturating_sub(1);
        // Word k holds cells 32k … 32k + 31: 33 offsets, compared pairwise.
        let bits = |k: usize| {
            let s = &cell_start[WORD_CELLS * k..(WORD_CELLS * k + WORD_CELLS + 1).min(cells + 1)];
            s.windows(2).enumerate().fold(0u32, |w, (j, p)| w | (((p[1] > p[0]) as u32) << j))
        };
        let words = cells.div_ceil(WORD_CELLS);
        // The starts of the occupied cells of words `first..`, in order, written to `out`.
        let gather = |first: usize, ws: &[OccupancyWord], out: &mut [u32]| {
            let mut o = 0;
            for (k, w) in ws.iter().enumerate() {
                let mut b = w.bits;
                while b != 0 {
                    out[o] = cell_start[WORD_CELLS * (first + k) + b.trailing_zeros() as usize];
                    o += 1;
                    b &= b - 1;
                }
            }
        };
        // Words per parallel chunk (128k cells).
        const CHUNK: usize = 4096;
        let mut occupied = Vec::with_capacity(words);
        #[cfg(feature = "parallel")]
        {
            use rayon::prelude::*;
            occupied.par_extend((0..words).into_par_iter().map(|k| OccupancyWord { bits: bits(k), rank: 0 }));
        }
        #[cfg(not(feature = "parallel"))]
        occupied.extend((0..words).map(|k| OccupancyWord { bits: bits(k), rank: 0 }));
        let rank = OccupancyWord::rank_all(&mut occupied);
        let mut ref_start = vec![0; rank as usize + 1];
        ref_start[rank as usize] = refs.len() as u32;
        // Chunk c's occupied cells go to ref_start[rank of its first word ..].
        let chunk_rank = |c: usize| occupied.get(c * CHUNK).map_or(rank, |w| w.rank) as usize;
        let parts = crate::build::split_lengths(
            &mut ref_start[..rank as usize],
            (0..words.div_ceil(CHUNK)).map(|c| chunk_rank(c + 1) - chunk_rank(c)),
        );
        #[cfg(feature = "parallel")]
        {
            use rayon::prelude::*;
            parts
                .into_par_iter()
                .enumerate()
                .for_each(|(c, part)| gather(c * CHUNK, &occupied[c * CHUNK..((c + 1) * CHUNK).min(words)], part));
        }
        #[cfg(not(feature = "parallel"))]
        for (c, part) in parts.into_iter().enumerate() {
            gather(c * CHUNK, &occupied[c * CHUNK..((c + 1) * CHUNK).min(words)], part);
        }
        FlatGrid { geom, occupied, ref_start, refs, planes: Vec::new() }
    }

    /// The table of M + 1 offsets the builds produce (cell `c` owns
    /// `refs[t[c]..t[c + 1]]`), which `new` compacts: for digests and tests (the CPU and GPU
    /// kernels read the compact arrays).
    pub fn cell_table(&self) -> Vec<u32> {
        let cells = self.geom.cell_count() as usize;
        let mut t = Vec::with_capacity(cells + 1);
        let mut j = 0usize;
        for c in 0..cells {
            // An empty cell starts (and ends) where the next occupied cell starts.
            t.push(self.ref_start[j]);
            if self.is_occupied(c) {
                j += 1;
            }
        }
        t.push(self.refs.len() as u32);
        t
    }

    /// Whether cell `index` holds references.
    #[inline]
    pub fn is_occupied(&self, index: usize) -> bool {
        (self.occupied[index / WORD_CELLS].bits >> (index % WORD_CELLS)) & 1 != 0
    }

    /// Triangle indices in cell `index`; an empty cell costs a bit test.
    #[inline]
    pub fn cell(&self, index: usize) -> &[u32] {
        if !self.is_occupied(index) {
            return &[];
        }
        self.refs_of(index)
    }

    /// The references of cell `index`, which must be occupied: its rank among the occupied
    /// cells (the word's rank plus the occupied cells before it in the word) indexes
    /// `ref_start`.
    #[inline]
    pub(crate) fn refs_of(&self, index: usize) -> &[u32] {
        self.refs_at(self.rank(index))
    }

    /// The references of the `j`-th occupied cell (in [`FlatGrid::ref_start`]'s order).
    #[inline]
    pub(crate) fn refs_at(&self, j: usize) -> &[u32] {
        &self.refs[self.ref_start[j] as usize..self.ref_start[j + 1] as usize]
    }

    /// The entry of occupied cell `index` in [`FlatGrid::ref_start`]: its word's rank plus the
    /// occupied cells before it in the word.
    #[inline]
    pub(crate) fn rank(&self, index: usize) -> usize {
        let w = self.occupied[index / WORD_CELLS];
        let below = (1u32 << (index % WORD_CELLS)) - 1;
        (w.rank + (w.bits & below).count_ones()) as usize
    }

    /// Whether the walk of `search` ends in cell `index`, which it leaves at `t_exit`: the
    /// cell's triangles are tested (an empty cell only checks the best hit so far). With `slab`
    /// (the search's ray in this grid's space, when the grid has slabs, and the cell's
    /// coordinates) an occupied cell whose slab the ray's segment misses is passed as an empty
    /// one ([`crate::cell_plane`]). The caller counts the visited cells
    /// ([`crate::traversal::walk_counted`]).
    #[inline(always)]
    pub fn visit(&self, search: &mut ClosestHit, slab: Option<(&CellRay, UVec3)>, index: usize, t_exit: f32) -> bool {
        // Most cells are empty: their check stays in the walk's loop, and the tests of an
        // occupied cell are a call, which keeps that loop small enough to be compiled into the
        // walk (measured: a third fewer cycles per ray than one out-of-line visit per cell).
        if !self.is_occupied(index) {
            return search.done_at(t_exit);
        }
        self.test_occupied(search, slab, index, t_exit)
    }

    /// The tests of cell `index`, which holds references, unless `slab`'s segment misses the
    /// cell's slab (see [`FlatGrid::visit`]).
    #[inline(never)]
    pub(crate) fn test_occupied(
        &self,
        search: &mut ClosestHit,
        slab: Option<(&CellRay, UVec3)>,
        index: usize,
        t_exit: f32,
    ) -> bool {
        let j = self.rank(index);
        if self.slab_misses(slab, j, t_exit) {
            return search.done_at(t_exit);
        }
        search.test_cell(self.refs_at(j), t_exit)
    }

    /// Whether the occupied cell of rank `j` has a slab that the segment of `slab`'s ray in its
    /// cell, up to `t_exit`, misses.
    #[inline(always)]
    pub(crate) fn slab_misses(&self, slab: Option<(&CellRay, UVec3)>, j: usize, t_exit: f32) -> bool {
        match (slab, self.planes.get(j)) {
            (Some((r, c)), Some(p)) if p.lo > f32::NEG_INFINITY => p.misses(r, c, t_exit),
            _ => false,
        }
    }

    /// The search's ray in this grid's space for the slab checks, when the grid has slabs.
    #[inline(always)]
    pub fn cell_ray(&self, ray: &crate::geometry::GridRay) -> Option<CellRay> {
        (!self.planes.is_empty()).then(|| CellRay::new(ray))
    }

    pub fn memory_bytes(&self) -> u64 {
        (self.ref_start.len() + self.refs.len()) as u64 * 4
            + (self.occupied.len() * size_of::<OccupancyWord>()) as u64
            + (self.planes.len() * size_of::<CellPlane>()) as u64
    }

    /// Size figures of the grid alone (one level).
    pub fn stats(&self, triangles: usize) -> StructureStats {
        let cells = self.geom.cell_count();
        let occupied = self.ref_start.len() as u64 - 1;
        StructureStats {
            resolution: self.geom.res.to_array(),
            nodes: 1,
            levels: 1,
            cells,
            empty_cells: cells - occupied,
            refs: self.refs.len() as u64,
            depth_histogram: vec![1],
            ..StructureStats::sized(self.memory_bytes(), triangles)
        }
    }

    /// Builds the grid `geom` over `tris`. Timings are appended to `times`.
    pub fn build(
        tris: &[[Vec3; 3]],
        geom: GridGeometry,
        opts: BuildOptions,
        times: &mut PhaseTimes,
    ) -> Result<FlatGrid, BuildError> {
        FlatGrid::build_reusing(tris, geom, opts, times, &mut BuildScratch::default())
    }

    /// [`FlatGrid::build`] into the arrays of `scratch` (see [`BuildScratch`]): the same grid,
    /// without the page faults of fresh memory when `scratch` holds a previous build's arrays.
    /// The serial build ignores `scratch`.
    pub fn build_reusing(
        tris: &[[Vec3; 3]],
        geom: GridGeometry,
        opts: BuildOptions,
        times: &mut PhaseTimes,
        scratch: &mut BuildScratch,
    ) -> Result<FlatGrid, BuildError> {
        if tris.len() as u64 >= u32::MAX as u64 {
            return Err(BuildError::TooManyTriangles(tris.len() as u64));
        }
        #[cfg(feature = "parallel")]
        if opts.parallel {
            return crate::build::on_pool(|| {
                crate::build::parallel::flat_grid_reusing(tris, &geom, opts.insert, times, scratch)
            });
        }
        let _ = scratch;
        let (cell_start, refs) = bucket::bucket(tris, None, &geom, opts.insert, INSERT_MARGIN_CELLS, Some(times))?;
        Ok(times.record("cell bits", || FlatGrid::new(geom, cell_start, refs)))
    }
}
