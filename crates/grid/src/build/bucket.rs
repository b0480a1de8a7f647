//! The serial bucketing of triangles into a grid's cells: count → prefix sum → scatter (survey
//! Algorithm 1), references increasing within each cell. Used by the flat grid and by every
//! node of the hierarchical grids.

use glam::{UVec3, Vec3};
use web_time::Instant;

use super::{PhaseTimes, check_refs, zeroed};
use crate::BuildError;
use crate::geometry::GridGeometry;
use crate::insert::{InsertMode, box_cell_range, for_each_cell, prepare};

/// Exclusive prefix sum of per-cell counts into `cell_start` (M + 1 entries).
pub fn prefix_sum(counts: impl Iterator<Item = u32>, cells: usize) -> Result<Vec<u32>, BuildError> {
    let mut start = Vec::with_capacity(cells + 1);
    let mut acc = 0u64;
    for c in counts {
        start.push(acc as u32);
        acc += c as u64;
        check_refs(acc)?;
    }
    start.push(acc as u32);
    Ok(start)
}

/// The references bounding-box insertion of the triangles `ids` into `geom` makes (every cell of
/// a triangle's box range), counted from the ranges alone without visiting a cell: the same
/// count [`bucket`] reaches in [`InsertMode::BoundingBox`], and an upper bound on it in
/// [`InsertMode::Exact`].
pub fn box_references(tris: &[[Vec3; 3]], ids: &[u32], geom: &GridGeometry, margin: f64) -> u64 {
    ids.iter()
        .map(|&i| {
            // `prepare`'s range, without the triangle in f64 that only exact insertion reads.
            let [lo, hi] = box_cell_range(geom, &tris[i as usize], margin as f32);
            let e = hi - lo + UVec3::ONE;
            e.x as u64 * e.y as u64 * e.z as u64
        })
        .sum()
}

/// Buckets the triangles `ids` (or all of `tris` when `None`) into the cells of `geom`: the
/// serial count → prefix sum → scatter of survey Algorithm 1. Returns `cell_start` (M + 1
/// offsets) and the references, increasing within each cell. Used by the flat grid and by
/// every node of the hierarchical grids.
pub fn bucket(
    tris: &[[Vec3; 3]],
    ids: Option<&[u32]>,
    geom: &GridGeometry,
    mode: InsertMode,
    margin: f64,
    times: Option<&mut PhaseTimes>,
) -> Result<Buckets, BuildError> {
    let bucketed = bucket_within(tris, ids, geom, mode, margin, u64::MAX, times)?;
    Ok(bucketed.expect("no reference limit"))
}

/// A bucketing's `cell_start` (M + 1 offsets) and references.
pub type Buckets = (Vec<u32>, Vec<u32>);

/// [`bucket`], or `None` without the scatter when the references would be more than `limit`
/// (known after the count).
pub fn bucket_within(
    tris: &[[Vec3; 3]],
    ids: Option<&[u32]>,
    geom: &GridGeometry,
    mode: InsertMode,
    margin: f64,
    limit: u64,
    mut times: Option<&mut PhaseTimes>,
) -> Result<Option<Buckets>, BuildError> {
    let cells = geom.cell_count() as usize;
    let n = ids.map_or(tris.len(), |v| v.len());
    let id = |k: usize| ids.map_or(k as u32, |v| v[k]);
    let mut record = |name: &str, start: Instant| {
        if let Some(t) = times.as_deref_mut() {
            t.record_since(name, start);
        }
    };
    let start = Instant::now();
    let mut counts = zeroed::<u32>(cells, "cell counts")?;
    let mut upper = 0u64;
    for k in 0..n {
        let g = prepare(geom, &tris[id(k) as usize], margin);
        // Refuse a grid over the reference limit before visiting its cells one by one (the
        // box's cell count bounds the triangle's references from above).
        let e = g.hi - g.lo + UVec3::ONE;
        upper += e.x as u64 * e.y as u64 * e.z as u64;
        if mode == InsertMode::BoundingBox {
            check_refs(upper)?;
        }
        for_each_cell(geom, &g, mode, |c| counts[c] += 1);
    }
    record("count", start);
    let start = Instant::now();
    let cell_start = prefix_sum(counts.iter().copied(), cells)?;
    record("scan", start);
    if cell_start[cells] as u64 > limit {
        return Ok(None);
    }
    let start = Instant::now();
    let mut cursor = counts;
    cursor.copy_from_slice(&cell_start[..cells]);
    let mut refs = zeroed::<u32>(cell_start[cells] as usize, "triangle references")?;
    for k in 0..n {
        let i = id(k);
        let g = prepare(geom, &tris[i as usize], margin);
        for_each_cell(geom, &g, mode, |c| {
            refs[cursor[c] as usize] = i;
            cursor[c] += 1;
        });
    }
    record("scatter", start);
    Ok(Some((cell_start, refs)))
}
