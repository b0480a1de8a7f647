//! The parallel bucketing of a flat grid: the grid is split into slabs of z layers (contiguous
//! ranges of cells, so of `cell_start` and `refs` too); triangles are binned by the slabs they
//! touch, in increasing order, and each slab counts and scatters its own cells without atomics.
//! The output is therefore bit-identical to the serial [`super::bucket::bucket`], with no sort.
//! Slabs are thin enough (at most [`SLAB_CELLS`]) that a slab's part of the cell table stays in
//! cache, and each triangle's cell range is prepared once and copied into the slabs it meets,
//! so a slab reads its triangles in sequence.

use glam::{UVec3, Vec3};
use rayon::prelude::*;

use super::{PhaseTimes, check_refs, split_lengths};
use crate::BuildError;
use crate::geometry::{GridGeometry, INSERT_MARGIN_CELLS, MAX_AXIS_RES};
use crate::insert::{InsertMode, box_cell_range, for_each_box_cell_in_layers, for_each_cell_in_layers, prepare};

/// In-place inclusive prefix sum of `counts` in two parallel passes (chunk sums, then each
/// chunk's running sum from its offset); returns the total.
fn par_inclusive_scan(counts: &mut [u32]) -> Result<u64, BuildError> {
    const CHUNK: usize = 1 << 16;
    let sums: Vec<u64> = counts.par_chunks(CHUNK).map(|c| c.iter().map(|&x| x as u64).sum()).collect();
    let mut offsets = Vec::with_capacity(sums.len());
    let mut total = 0u64;
    for s in sums {
        offsets.push(total);
        total += s;
    }
    check_refs(total)?;
    counts.par_chunks_mut(CHUNK).zip(offsets).for_each(|(c, offset)| {
        // Fits: every partial sum is at most `total` ≤ MAX_REFS < 2³².
        let mut acc = offset as u32;
        for x in c {
            acc += *x;
            *x = acc;
        }
    });
    Ok(total)
}

/// The cells triangle `tri` (prepared cell range `cells`) goes into within `layers`: the range
/// itself for bounding-box insertion, else the exact test.
#[inline(always)]
fn cells_of_triangle(
    geom: &GridGeometry,
    tri: &[Vec3; 3],
    cells: [UVec3; 2],
    mode: InsertMode,
    layers: std::ops::Range<u32>,
    f: impl FnMut(usize),
) {
    match mode {
        InsertMode::BoundingBox => {
            for_each_box_cell_in_layers(geom, cells, layers, f);
        }
        InsertMode::Exact => {
            let g = prepare(geom, tri, INSERT_MARGIN_CELLS);
            for_each_cell_in_layers(geom, &g, mode, layers, f);
        }
    }
}

/// A triangle's cell range, each corner's three indices in 10 bits of a word (every axis has at
/// most [`MAX_AXIS_RES`] = 2^10 cells): a third of the bytes of two `UVec3`, so binning, counting
/// and scattering move less memory.
#[derive(Clone, Copy, Default)]
struct CellBox([u32; 2]);

const _: () = assert!(MAX_AXIS_RES <= 1 << 10);

impl CellBox {
    #[inline(always)]
    fn pack([lo, hi]: [UVec3; 2]) -> CellBox {
        let word = |v: UVec3| v.x | v.y << 10 | v.z << 20;
        CellBox([word(lo), word(hi)])
    }
    #[inline(always)]
    fn unpack(self) -> [UVec3; 2] {
        let v = |w: u32| UVec3::new(w & 0x3ff, (w >> 10) & 0x3ff, w >> 20);
        [v(self.0[0]), v(self.0[1])]
    }
    #[inline(always)]
    fn z_range(self) -> (u32, u32) {
        (self.0[0] >> 20, self.0[1] >> 20)
    }
}

/// One chunk of triangles sorted by slab: slab `s` owns `items[start[s]..start[s + 1]]`, each a
/// triangle index and its cell range, in increasing index order.
struct SlabBins {
    items: Vec<(u32, CellBox)>,
    start: Vec<u32>,
}

/// Most cells in one slab: 128k cells, 512 KiB of the cell table.
const SLAB_CELLS: usize = 1 << 17;

/// [`super::bucket::bucket`] over all of `tris` on all threads, with the same output, written
/// into `scratch`'s M + 1 table and references (taken out of it; their memory reused).
pub fn bucket_reusing(
    tris: &[[Vec3; 3]],
    geom: &GridGeometry,
    mode: InsertMode,
    times: &mut PhaseTimes,
    scratch: &mut super::BuildScratch,
) -> Result<(Vec<u32>, Vec<u32>), BuildError> {
    let geom = *geom;
    let cells = geom.cell_count() as usize;
    let layer = geom.res.x as usize * geom.res.y as usize;
    let nz = geom.res.z;
    // Several slabs per thread so that work stealing evens out dense and sparse slabs, and
    // slabs small enough that a slab's part of the cell table stays in cache while its
    // triangles, in any order, count and scatter into it (particles in random order made the
    // build super-linear in N).
    let few = (rayon::current_num_threads() * 2).clamp(1, nz as usize);
    let layout = |slabs: usize| {
        let edge: Vec<u32> = (0..=slabs).map(|s| (s as u64 * nz as u64 / slabs as u64) as u32).collect();
        let mut slab_of_layer = vec![0u32; nz as usize];
        for s in 0..slabs {
            slab_of_layer[edge[s] as usize..edge[s + 1] as usize].fill(s as u32);
        }
        (edge, slab_of_layer)
    };
    // Each triangle's cell range, prepared once (count and scatter read it); a slab visits the
    // triangles whose z layers meet it, in increasing order. The ranges' cells bound the
    // references from above (exactly, for box insertion): a grid far over the limit is refused
    // before its cells are visited one by one (a fine grid over long slivers would otherwise
    // take minutes to fail).
    let (boxes, upper): (Vec<CellBox>, u64) = times.record("bin", || {
        let boxes: Vec<CellBox> =
            tris.par_iter().map(|t| CellBox::pack(box_cell_range(&geom, t, INSERT_MARGIN_CELLS as f32))).collect();
        let upper = boxes
            .par_iter()
            .map(|b| {
                let [lo, hi] = b.unpack();
                let e = hi - lo + UVec3::ONE;
                e.x as u64 * e.y as u64 * e.z as u64
            })
            .sum();
        (boxes, upper)
    });
    if mode == InsertMode::BoundingBox {
        check_refs(upper)?;
    }
    // A triangle is copied into every slab it meets: with triangles spanning many thin slabs
    // (long slivers across the scene) the copies could outgrow the grid, so the copies are held
    // to four per triangle on average: thin slabs when they allow it, else as many as the
    // threads share, else one.
    let many = few.max(cells.div_ceil(SLAB_CELLS)).min(nz as usize);
    let (slabs, edge, bins) = times.record("bin", || {
        let (slabs, (edge, slab_of_layer)) = [many, few, 1]
            .into_iter()
            .map(|n| (n, layout(n)))
            .find(|(_, (_, of))| {
                let pairs: u64 = boxes
                    .par_iter()
                    .map(|b| {
                        let (z0, z1) = b.z_range();
                        (of[z1 as usize] - of[z0 as usize]) as u64 + 1
                    })
                    .sum();
                pairs <= 4 * tris.len() as u64
            })
            .expect("one slab holds each triangle once");
        // The triangles of each slab with their cell ranges (copied, so that a slab reads them
        // in sequence), in increasing order: each chunk of triangles sorts its own by slab (a
        // counting sort), and a slab reads its run of every chunk, chunks in order.
        const CHUNK: usize = 1 << 14;
        let slab_range = |b: &CellBox| {
            let (z0, z1) = b.z_range();
            slab_of_layer[z0 as usize] as usize..=slab_of_layer[z1 as usize] as usize
        };
        let bins: Vec<SlabBins> = boxes
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(k, part)| {
                let mut start = vec![0u32; slabs + 1];
                for b in part {
                    for s in slab_range(b) {
                        start[s + 1] += 1;
                    }
                }
                for s in 0..slabs {
                    start[s + 1] += start[s];
                }
                let mut next = start.clone();
                let mut items = vec![(0u32, CellBox::default()); start[slabs] as usize];
                for (j, b) in part.iter().enumerate() {
                    for s in slab_range(b) {
                        items[next[s] as usize] = ((k * CHUNK + j) as u32, *b);
                        next[s] += 1;
                    }
                }
                SlabBins { items, start }
            })
            .collect();
        (slabs, edge, bins)
    });
    drop(boxes);
    let in_slab =
        |s: usize| bins.iter().flat_map(move |b| b.items[b.start[s] as usize..b.start[s + 1] as usize].iter().copied());
    let slab_cells = |s: usize| (edge[s + 1] - edge[s]) as usize * layer;
    // `offsets` becomes `cell_start` in place (Lagae & Dutré): counts, then their inclusive
    // prefix sum (each cell's end), then the scatter decrements each cell's end once per
    // reference, filling the cell backwards, so each entry ends at its cell's start. No
    // cursor array, no second M-sized allocation.
    // Both zero-filled on all threads (see `refill_par`); the time is the phase's that needs it.
    let mut offsets = std::mem::take(&mut scratch.cell_table);
    times.record("count", || super::refill_par(&mut offsets, cells + 1, "the cell table"))?;
    times.record("count", || {
        split_lengths(&mut offsets[..cells], (0..slabs).map(slab_cells)).into_par_iter().enumerate().for_each(
            |(s, part)| {
                let base = edge[s] as usize * layer;
                for (i, b) in in_slab(s) {
                    let layers = edge[s]..edge[s + 1];
                    cells_of_triangle(&geom, &tris[i as usize], b.unpack(), mode, layers, |c| part[c - base] += 1);
                }
            },
        )
    });
    let total = times.record("scan", || par_inclusive_scan(&mut offsets[..cells]))?;
    offsets[cells] = total as u32;
    let mut refs = std::mem::take(&mut scratch.refs);
    times.record("scatter", || super::refill_par(&mut refs, total as usize, "triangle references"))?;
    times.record("scatter", || {
        // A slab's references start where the cell before it ends.
        let slab_start = |s: usize| {
            let base = edge[s] as usize * layer;
            if base == 0 { 0 } else { offsets[base - 1] as usize }
        };
        let ref_bounds: Vec<usize> =
            (0..=slabs).map(|s| if s == slabs { total as usize } else { slab_start(s) }).collect();
        let ref_parts = split_lengths(&mut refs, ref_bounds.windows(2).map(|w| w[1] - w[0]));
        let end_parts = split_lengths(&mut offsets[..cells], (0..slabs).map(slab_cells));
        ref_parts.into_par_iter().zip(end_parts).enumerate().for_each(|(s, (out, end))| {
            let base = edge[s] as usize * layer;
            let ref_base = ref_bounds[s] as u32;
            // Backwards, so that each cell, filled from its end, holds increasing indices.
            for (i, b) in in_slab(s).rev() {
                let layers = edge[s]..edge[s + 1];
                cells_of_triangle(&geom, &tris[i as usize], b.unpack(), mode, layers, |c| {
                    let e = &mut end[c - base];
                    *e -= 1;
                    out[(*e - ref_base) as usize] = i;
                });
            }
        });
    });
    Ok((offsets, refs))
}
