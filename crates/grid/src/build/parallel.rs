//! The parallel build of a flat grid: the grid is split into slabs of z layers (contiguous
//! ranges of cells, so of the occupied cells' offsets and of `refs` too); triangles are binned
//! by the slabs they touch, in increasing order, and each slab counts and scatters its own
//! cells without atomics. The output is therefore bit-identical to the serial
//! [`super::bucket::bucket`] compacted by [`FlatGrid::new`], with no sort.
//! Slabs are thin enough (at most [`SLAB_CELLS`]) that a slab's table of counts, a per-thread
//! table reused between builds, stays in cache; a slab keeps only its occupied cells' counts,
//! so no array of M entries is written but the occupancy bits. Each triangle's cell range is
//! prepared once and copied into the slabs it meets, so a slab reads its triangles in sequence.

use glam::{UVec3, Vec3};
use rayon::prelude::*;

use super::{PhaseTimes, check_refs, split_lengths};
use crate::BuildError;
use crate::flat::{FlatGrid, OccupancyWord, WORD_CELLS};
use crate::geometry::{GridGeometry, INSERT_MARGIN_CELLS, MAX_AXIS_RES};
use crate::insert::{InsertMode, box_cell_range, for_each_run_in_layers, prepare};

/// The runs of cells triangle `tri` goes into within `layers` under exact insertion (box
/// insertion's cells come from the range alone, see [`for_each_box_cell`]).
#[inline(always)]
fn exact_runs(
    geom: &GridGeometry,
    tri: &[Vec3; 3],
    layers: std::ops::Range<u32>,
    f: impl FnMut(std::ops::Range<usize>),
) {
    let g = prepare(geom, tri, INSERT_MARGIN_CELLS);
    for_each_run_in_layers(geom, &g, InsertMode::Exact, layers, f);
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
    /// The slabs the range meets (its copies when binned), `slab_of_layer` the slab of each z
    /// layer.
    #[inline(always)]
    fn slabs(self, slab_of_layer: &[u32]) -> std::ops::RangeInclusive<usize> {
        let (z0, z1) = self.z_range();
        slab_of_layer[z0 as usize] as usize..=slab_of_layer[z1 as usize] as usize
    }
    /// How many slabs the range meets.
    #[inline(always)]
    fn slabs_met(self, slab_of_layer: &[u32]) -> u64 {
        let r = self.slabs(slab_of_layer);
        (r.end() - r.start()) as u64 + 1
    }
}

/// One chunk of triangles sorted by slab: slab `s` owns `items[start[s]..start[s + 1]]`, each a
/// triangle index and its cell range, in increasing index order.
struct SlabBins {
    items: Vec<(u32, CellBox)>,
    start: Vec<u32>,
    /// Per slab, the cells of its triangles' ranges within it: its references under
    /// bounding-box insertion.
    box_cells: Vec<u64>,
}

/// Most cells in one slab: 128k cells, 512 KiB of the cell table.
const SLAB_CELLS: usize = 1 << 17;

/// Triangles binned together: their cell ranges (128 KiB) stay in cache between the chunk's
/// counting and placing passes.
const BIN_CHUNK: usize = 1 << 14;

/// The flat grid of [`super::bucket::bucket`] over all of `tris` on all threads, bit-identical
/// to the serial build's, written into `scratch`'s arrays (taken out of it; their memory reused).
pub fn flat_grid_reusing(
    tris: &[[Vec3; 3]],
    geom: &GridGeometry,
    mode: InsertMode,
    times: &mut PhaseTimes,
    scratch: &mut super::BuildScratch,
) -> Result<FlatGrid, BuildError> {
    let geom = *geom;
    let cells = geom.cell_count() as usize;
    let layer = geom.res.x as usize * geom.res.y as usize;
    let nz = geom.res.z;
    // Several slabs per thread so that work stealing evens out dense and sparse slabs, and
    // slabs small enough that a slab's part of the cell table stays in cache while its
    // triangles, in any order, count and scatter into it (particles in random order made the
    // build super-linear in N).
    let few = (rayon::current_num_threads() * 4).clamp(1, nz as usize);
    let layout = |slabs: usize| {
        let edge: Vec<u32> = (0..=slabs).map(|s| (s as u64 * nz as u64 / slabs as u64) as u32).collect();
        let mut slab_of_layer = vec![0u32; nz as usize];
        for s in 0..slabs {
            slab_of_layer[edge[s] as usize..edge[s + 1] as usize].fill(s as u32);
        }
        (edge, slab_of_layer)
    };
    // A triangle is copied into every slab it meets: with triangles spanning many thin slabs
    // (long slivers across the scene) the copies could outgrow the grid, so the copies are held
    // to a few per triangle: thin slabs when they allow it, else as many as the threads share,
    // else one.
    let many = few.max(cells.div_ceil(SLAB_CELLS)).min(nz as usize);
    // The triangles of each slab with their cell ranges (copied, so that a slab reads them in
    // sequence), in increasing order: each chunk of triangles sorts its own by slab (a counting
    // sort), and a slab reads its run of every chunk, chunks in order. Any layout gives the same
    // grid; it only decides how the work is cut.
    // `start[s + 1]`: the copies of `part`'s ranges slab `s` gets (counted by the caller).
    let place = |k: usize, part: &[CellBox], mut start: Vec<u32>, edge: &[u32], slab_of_layer: &[u32]| {
        let slabs = start.len() - 1;
        for s in 0..slabs {
            start[s + 1] += start[s];
        }
        let mut next = start.clone();
        let mut items = vec![(0u32, CellBox::default()); start[slabs] as usize];
        let mut box_cells = vec![0u64; slabs];
        for (j, b) in part.iter().enumerate() {
            let [lo, hi] = b.unpack();
            let row_cells = (hi.x - lo.x + 1) as u64 * (hi.y - lo.y + 1) as u64;
            for s in b.slabs(slab_of_layer) {
                items[next[s] as usize] = ((k * BIN_CHUNK + j) as u32, *b);
                next[s] += 1;
                let layers = hi.z.min(edge[s + 1] - 1) + 1 - lo.z.max(edge[s]);
                box_cells[s] += row_cells * layers as u64;
            }
        }
        SlabBins { items, start, box_cells }
    };
    let count_copies = |b: CellBox, start: &mut [u32], slab_of_layer: &[u32]| {
        for s in b.slabs(slab_of_layer) {
            start[s + 1] += 1;
        }
    };
    let bin_chunk = |k: usize, part: &[CellBox], slabs: usize, edge: &[u32], slab_of_layer: &[u32]| {
        let mut start = vec![0u32; slabs + 1];
        part.iter().for_each(|&b| count_copies(b, &mut start, slab_of_layer));
        place(k, part, start, edge, slab_of_layer)
    };
    let range_of = |t: &[Vec3; 3]| CellBox::pack(box_cell_range(&geom, t, INSERT_MARGIN_CELLS as f32));
    // First in one pass over the triangles: each chunk prepares its triangles' cell ranges in a
    // buffer of its thread's (in cache) and bins them into thin slabs, unless they would be
    // copied more than four times on average there (then the ranges are prepared again, kept
    // whole and a layout chosen over all of them, below). One read of the triangles, no array of
    // ranges through memory.
    let thin = times.record("bin", || {
        let (edge, slab_of_layer) = layout(many);
        let bins: Option<Vec<SlabBins>> = tris
            .par_chunks(BIN_CHUNK)
            .enumerate()
            .map(|(k, part)| {
                CHUNK_BOXES.with(|boxes| {
                    let mut boxes = boxes.borrow_mut();
                    boxes.clear();
                    // The ranges and their copies per slab in one pass.
                    let mut start = vec![0u32; many + 1];
                    boxes.extend(part.iter().map(|t| {
                        let b = range_of(t);
                        count_copies(b, &mut start, &slab_of_layer);
                        b
                    }));
                    let pairs: u64 = start.iter().map(|&n| n as u64).sum();
                    (pairs <= 4 * part.len() as u64).then(|| place(k, &boxes, start, &edge, &slab_of_layer))
                })
            })
            .collect();
        bins.map(|b| (many, edge, b))
    });
    let (slabs, edge, bins) = match thin {
        Some(t) => t,
        None => times.record("bin", || {
            let boxes: Vec<CellBox> = tris.par_iter().map(range_of).collect();
            let (slabs, (edge, slab_of_layer)) = [many, few, 1]
                .into_iter()
                .map(|n| (n, layout(n)))
                .find(|(_, (_, of))| {
                    let pairs: u64 = boxes.par_iter().map(|b| b.slabs_met(of)).sum();
                    pairs <= 4 * tris.len() as u64
                })
                .expect("one slab holds each triangle once");
            let bins: Vec<SlabBins> = boxes
                .par_chunks(BIN_CHUNK)
                .enumerate()
                .map(|(k, part)| bin_chunk(k, part, slabs, &edge, &slab_of_layer))
                .collect();
            (slabs, edge, bins)
        }),
    };
    // The ranges' cells, summed by the binning, are the references of box insertion: a grid far
    // over the limit is refused before its cells are visited one by one (a fine grid over long
    // slivers would otherwise take minutes to fail).
    if mode == InsertMode::BoundingBox {
        check_refs(bins.iter().flat_map(|b| &b.box_cells).sum())?;
    }
    let in_slab =
        |s: usize| bins.iter().flat_map(move |b| b.items[b.start[s] as usize..b.start[s + 1] as usize].iter().copied());
    let slab_base: Vec<usize> = edge.iter().map(|&z| z as usize * layer).collect();
    // A box range's part in slab `s`: its first cell, relative to the slab's, and its extent.
    let (rx, ry) = (geom.res.x as usize, geom.res.y as usize);
    let stride = [1, rx, layer];
    let slab_part = |s: usize| {
        let (base, z_first, z_last) = (slab_base[s], edge[s], edge[s + 1] - 1);
        #[inline(always)]
        move |b: CellBox| -> (usize, [u32; 3]) {
            let [lo, hi] = b.unpack();
            let (z0, z1) = (lo.z.max(z_first), hi.z.min(z_last));
            let first = lo.x as usize + rx * (lo.y as usize + ry * z0 as usize) - base;
            (first, [hi.x - lo.x + 1, hi.y - lo.y + 1, z1 + 1 - z0])
        }
    };
    // Ranges of at most 2 × 2 × 2 cells (most triangles' at the auto resolution) skip the
    // loops, whose short and varying trip counts the branch predictor missed.
    let small = |e: [u32; 3]| e[0] <= 2 && e[1] <= 2 && e[2] <= 2;
    // Such a range's candidate k (x + 2y + 4z) from its first cell.
    let candidate = |first: usize, k: usize| first + (k & 1) + rx * ((k >> 1) & 1) + layer * (k >> 2);
    // Each slab counts its cells' references in a table of its own (in cache, reused between
    // builds) and keeps only which of its cells are occupied and their counts: no M-sized
    // table, no pass over every cell but the slab's own. The scatter turns the table into each
    // occupied cell's next free place in the slab's references (empty cells are never
    // written) and writes them.
    let count = |s: usize, table: &mut [u32]| {
        let last = table.len() - 1;
        let slab_box = slab_part(s);
        for (i, b) in in_slab(s) {
            if mode == InsertMode::Exact {
                let base = slab_base[s];
                exact_runs(&geom, &tris[i as usize], edge[s]..edge[s + 1], |r| {
                    table[r.start - base..r.end - base].iter_mut().for_each(|n| *n += 1)
                });
                continue;
            }
            let (first, e) = slab_box(b);
            if small(e) {
                // Each of the eight candidates adds whether it is in the range, with no loop;
                // a candidate outside is clamped into the table and adds 0.
                let (wx, wy, wz) = ((e[0] == 2) as u32, (e[1] == 2) as u32, (e[2] == 2) as u32);
                for (k, add) in [1, wx, wy, wx & wy, wz, wx & wz, wy & wz, wx & wy & wz].into_iter().enumerate() {
                    table[candidate(first, k).min(last)] += add;
                }
            } else {
                for_each_box_cell(first, e, stride, |c| table[c] += 1);
            }
        }
        SlabCounts::of(table)
    };
    let scatter = |s: usize, counted: &SlabCounts, next: &mut [u32], out: &mut [u32]| {
        counted.starts_into(next);
        let slab_box = slab_part(s);
        let mut put = |c: usize, i: u32| {
            let e = &mut next[c];
            out[*e as usize] = i;
            *e += 1;
        };
        for (i, b) in in_slab(s) {
            if mode == InsertMode::Exact {
                let base = slab_base[s];
                exact_runs(&geom, &tris[i as usize], edge[s]..edge[s + 1], |r| r.for_each(|c| put(c - base, i)));
                continue;
            }
            let (first, e) = slab_box(b);
            if small(e) {
                // One loop over the range's 1, 2, 4 or 8 cells: one trip count to guess.
                let wide = (e[0] == 2) as usize | ((e[1] == 2) as usize) << 1 | ((e[2] == 2) as usize) << 2;
                for &k in CANDIDATES[wide] {
                    put(candidate(first, k), i);
                }
            } else {
                for_each_box_cell(first, e, stride, |c| put(c, i));
            }
        }
    };
    let slab_cells = |s: usize| slab_base[s + 1] - slab_base[s];
    let prefix = |sizes: &mut dyn Iterator<Item = u64>| -> Vec<usize> {
        let mut acc = 0;
        std::iter::once(0)
            .chain(sizes.map(|n| {
                acc += n as usize;
                acc
            }))
            .collect()
    };
    let mut refs = std::mem::take(&mut scratch.refs);
    let (counted, ref_base) = if mode == InsertMode::BoundingBox {
        // A slab's references are its ranges' cells, known from the binning: each slab counts
        // and scatters at once, while its table and triangles are in cache.
        let ref_base = prefix(&mut (0..slabs).map(|s| bins.iter().map(|b| b.box_cells[s]).sum()));
        times.record("count and scatter", || {
            super::resize_for_overwrite(&mut refs, ref_base[slabs], "triangle references")
        })?;
        let counted: Vec<SlabCounts> = times.record("count and scatter", || {
            split_lengths(&mut refs, ref_base.windows(2).map(|w| w[1] - w[0]))
                .into_par_iter()
                .enumerate()
                .map(|(s, out)| {
                    with_slab_table(slab_cells(s), true, |table| {
                        let counted = count(s, table);
                        debug_assert_eq!(counted.refs, out.len() as u64, "slab {s}: its ranges' cells");
                        scatter(s, &counted, table, out);
                        counted
                    })
                })
                .collect::<Result<_, _>>()
        })?;
        (counted, ref_base)
    } else {
        let counted: Vec<SlabCounts> = times.record("count", || {
            (0..slabs)
                .into_par_iter()
                .map(|s| with_slab_table(slab_cells(s), true, |t| count(s, t)))
                .collect::<Result<_, _>>()
        })?;
        let ref_base = prefix(&mut counted.iter().map(|c| c.refs));
        check_refs(ref_base[slabs] as u64)?;
        times.record("scatter", || super::resize_for_overwrite(&mut refs, ref_base[slabs], "triangle references"))?;
        times.record("scatter", || {
            split_lengths(&mut refs, ref_base.windows(2).map(|w| w[1] - w[0])).into_par_iter().enumerate().try_for_each(
                |(s, out)| with_slab_table(slab_cells(s), false, |next| scatter(s, &counted[s], next, out)),
            )
        })?;
        (counted, ref_base)
    };
    let total = ref_base[slabs];
    let occupied_total: usize = counted.iter().map(|c| c.counts.len()).sum();
    let mut occupied = std::mem::take(&mut scratch.occupied);
    let mut ref_start = std::mem::take(&mut scratch.ref_start);
    times.record("cell bits", || -> Result<(), BuildError> {
        // Word k holds cells 32k … 32k + 31, which may lie in several slabs.
        let words = cells.div_ceil(WORD_CELLS);
        super::refill_par(&mut occupied, words, "the occupancy words")?;
        const CHUNK: usize = 4096;
        occupied.par_chunks_mut(CHUNK).enumerate().for_each(|(k0, part)| {
            let mut s = slab_base.partition_point(|&b| b <= k0 * CHUNK * WORD_CELLS) - 1;
            for (j, w) in part.iter_mut().enumerate() {
                let first = (k0 * CHUNK + j) * WORD_CELLS;
                let end = (first + WORD_CELLS).min(cells);
                let mut c = first;
                while c < end {
                    while slab_base[s + 1] <= c {
                        s += 1;
                    }
                    let len = end.min(slab_base[s + 1]) - c;
                    w.bits |= counted[s].bits_at(c - slab_base[s], len) << (c - first);
                    c += len;
                }
            }
        });
        OccupancyWord::rank_all(&mut occupied);
        super::refill_par(&mut ref_start, occupied_total + 1, "the cell offsets")?;
        ref_start[occupied_total] = total as u32;
        split_lengths(&mut ref_start[..occupied_total], counted.iter().map(|c| c.counts.len()))
            .into_par_iter()
            .zip(&counted)
            .zip(&ref_base)
            .for_each(|((out, c), &first)| {
                // Fits: every start is at most `total` ≤ MAX_REFS < 2³².
                let mut acc = first as u32;
                for (o, &n) in out.iter_mut().zip(&c.counts) {
                    *o = acc;
                    acc += n;
                }
            });
        Ok(())
    })?;
    Ok(FlatGrid::from_parts(geom, occupied, ref_start, refs))
}

/// `f` for each cell of a box of `extent` cells from cell `first`, a step along axis a adding
/// `stride[a]`, the innermost loop along the box's longest axis (a long thin range has one
/// long loop, not many of one or two trips). The cells come in no particular order: one
/// triangle's cells each get it once, so a cell's references stay in triangle order.
#[inline(always)]
fn for_each_box_cell(first: usize, extent: [u32; 3], stride: [usize; 3], mut f: impl FnMut(usize)) {
    let inner = if extent[0] >= extent[1] && extent[0] >= extent[2] {
        0
    } else if extent[1] >= extent[2] {
        1
    } else {
        2
    };
    let (a, b) = ((inner + 1) % 3, (inner + 2) % 3);
    let (n, step) = (extent[inner] as usize, stride[inner]);
    for p in 0..extent[b] as usize {
        for q in 0..extent[a] as usize {
            let mut c = first + p * stride[b] + q * stride[a];
            for _ in 0..n {
                f(c);
                c += step;
            }
        }
    }
}

/// For a cell range of at most 2 × 2 × 2 cells, by the axes on which it spans two cells (bit 0:
/// x, 1: y, 2: z), its cells as offsets k (x + 2y + 4z) from its first, in increasing cell
/// order.
const CANDIDATES: [&[usize]; 8] =
    [&[0], &[0, 1], &[0, 2], &[0, 1, 2, 3], &[0, 4], &[0, 1, 4, 5], &[0, 2, 4, 6], &[0, 1, 2, 3, 4, 5, 6, 7]];

/// What the count of one slab keeps: which of its cells hold references (bit i of word i / 32:
/// the slab's cell i) and how many, per occupied cell in order.
struct SlabCounts {
    bits: Vec<u32>,
    counts: Vec<u32>,
    refs: u64,
}

impl SlabCounts {
    /// The occupied cells of a slab's table of counts.
    fn of(table: &[u32]) -> SlabCounts {
        let mut bits = Vec::with_capacity(table.len().div_ceil(WORD_CELLS));
        let mut counts = Vec::new();
        for chunk in table.chunks(WORD_CELLS) {
            // A whole word's flags in a loop of fixed length, which compiles to SIMD compares.
            let w = match <&[u32; WORD_CELLS]>::try_from(chunk) {
                Ok(a) => (0..WORD_CELLS).fold(0u32, |w, j| w | ((a[j] != 0) as u32) << j),
                Err(_) => chunk.iter().enumerate().fold(0u32, |w, (j, &n)| w | ((n != 0) as u32) << j),
            };
            bits.push(w);
            let mut b = w;
            while b != 0 {
                counts.push(chunk[b.trailing_zeros() as usize]);
                b &= b - 1;
            }
        }
        let refs = counts.iter().map(|&n| n as u64).sum();
        SlabCounts { bits, counts, refs }
    }

    /// The occupancy of the slab's cells `from .. from + len` (`len` ≤ 32), cell `from` in bit 0.
    #[inline]
    fn bits_at(&self, from: usize, len: usize) -> u32 {
        let (k, o) = (from / WORD_CELLS, from % WORD_CELLS);
        let lo = self.bits[k] as u64;
        let hi = self.bits.get(k + 1).map_or(0, |&w| w as u64);
        let v = (lo | hi << 32) >> o;
        (v & ((1u64 << len) - 1)) as u32
    }

    /// Each occupied cell's first reference, relative to the slab's first, into `table`.
    fn starts_into(&self, table: &mut [u32]) {
        let mut acc = 0u32;
        let mut n = self.counts.iter();
        for (k, &w) in self.bits.iter().enumerate() {
            let mut b = w;
            while b != 0 {
                table[k * WORD_CELLS + b.trailing_zeros() as usize] = acc;
                acc += n.next().expect("a count per occupied cell");
                b &= b - 1;
            }
        }
    }
}

/// Largest per-thread table a build keeps for the next one (1 MiB): a slab's is at most
/// [`SLAB_CELLS`] cells unless a scene's slivers forced a few thick slabs.
const KEPT_TABLE_CELLS: usize = 1 << 18;

thread_local! {
    /// A chunk's cell ranges while it is binned ([`BIN_CHUNK`] of them).
    static CHUNK_BOXES: std::cell::RefCell<Vec<CellBox>> = const { std::cell::RefCell::new(Vec::new()) };
    static SLAB_TABLE: std::cell::RefCell<Vec<u32>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Runs `f` on a table of `cells` entries of this thread's, zeroed when `zero` (else holding
/// whatever the last user left).
/// [`BuildError::OutOfMemory`] when a table of `cells` cannot be had (one slab spans the grid
/// when long slivers cross it).
fn with_slab_table<R>(cells: usize, zero: bool, f: impl FnOnce(&mut [u32]) -> R) -> Result<R, BuildError> {
    SLAB_TABLE.with(|t| {
        let mut t = t.borrow_mut();
        if t.len() < cells {
            *t = super::zeroed(cells, "a slab's cell counts")?;
        } else if zero {
            t[..cells].fill(0);
        }
        let r = f(&mut t[..cells]);
        if t.len() > KEPT_TABLE_CELLS {
            *t = Vec::new();
        }
        Ok(r)
    })
}
