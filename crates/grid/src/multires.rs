//! Multi-resolution grids (Jevans & Wyvill 1989): top-down recursive subdivision. A cell whose
//! triangles are costly to test becomes a sub-grid of its own; leaves hold triangle lists.
//! Layout and traversal: [`crate::hierarchy`].
//!
//! # Build policies (the sub-grid resolution R of a cell with n triangles)
//! - [`Policy::Octree`]: R = 2×2×2 (an octree-like grid);
//! - [`Policy::Constant`]: R = k×k×k for every sub-grid;
//! - [`Policy::Adaptive`] (default): R from the cell's own triangle count, about λ·n cells,
//!   near-cubic (λ = [`MultiresOptions::density`]);
//! - [`Policy::MaxDepth`]: octree-like, every cell with more than `leaf_size` triangles is
//!   subdivided down to the depth limit, ignoring the cost model (the naive policy, for
//!   comparison).
//!
//! # When to subdivide (the survey's cost criterion)
//! For the first three policies a cell with n triangles is subdivided only while the sub-grid is
//! predicted cheaper than testing every triangle: Tsetup + m·Tstep + μ·Tinter < n·Tinter, where
//! m = ∛(R.x·R.y·R.z) and μ = N_m/m², N_m counted exactly by bucketing the n triangles into the
//! candidate sub-grid. [`MultiresOptions::max_depth`] guards the recursion, and so does the
//! f32 precision bound of [`crate::hierarchy::MAX_CHILD_MARGIN`].
//!
//! # A budget of references
//! The cost test weighs the tests a ray saves, not the memory a sub-grid takes: 20,000 copies
//! of one triangle across a cell pass it with 400 references per triangle (the tests per ray
//! fall by a tenth), and 50,000 triangles sharing a vertex keep every level's middle cell as
//! full as its parent, so the references multiply with depth (242M for 50k triangles). So a top
//! cell's subtree holds at most [`SUBTREE_REFS_PER_TRIANGLE`] references per triangle of the
//! cell: a sub-grid whose references exceed its budget stays a leaf, and its cells share the
//! budget in proportion to their references. Deterministic (a subtree's budget depends on its
//! own cells only), so the parallel build stays the serial one; on the shared scenes a
//! sub-grid holds at most 24 references per triangle of its cell (multires) and 46 (two-level,
//! box insertion), and none is over its budget.
//!
//! The build is deterministic; with `parallel` the subtrees of the top grid's cells are built
//! on all threads and concatenated in cell order, bit-identical to the serial build.

use glam::{UVec3, Vec3};
use gridrt_scene::Aabb;
use serde::{Deserialize, Serialize};

use crate::BuildError;
use crate::build::bucket::{box_references, bucket_within};
use crate::build::{BuildOptions, PhaseTimes, split_lengths};
use crate::flat::FlatGrid;
use crate::geometry::GridGeometry;
use crate::hierarchy::{CHILD, Hierarchy, MAX_CHILD_MARGIN, MAX_DEPTH, Node, cell_geometry, child_margin};
use crate::insert::InsertMode;
use crate::resolution::CostModel;

/// Largest sub-grid resolution per axis.
pub const MAX_SUB_RES: u32 = 64;

/// References a top cell's subtree may hold per triangle of the cell (module doc: a budget of
/// references).
pub const SUBTREE_REFS_PER_TRIANGLE: f64 = 64.0;

/// How sub-grid resolutions are chosen (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Policy {
    Octree,
    MaxDepth { leaf_size: u32 },
    Constant(u32),
    Adaptive,
}

impl std::str::FromStr for Policy {
    type Err = String;
    /// `octree | max-depth[=leaf_size] | constant[=k] | adaptive`
    fn from_str(s: &str) -> Result<Policy, String> {
        let (name, arg) = s.split_once('=').map_or((s, None), |(a, b)| (a, Some(b)));
        let num = |d: u32| arg.map_or(Ok(d), |v| v.parse::<u32>().map_err(|_| format!("bad number in \"{s}\"")));
        match name {
            "octree" => Ok(Policy::Octree),
            "adaptive" => Ok(Policy::Adaptive),
            "constant" => {
                let k = num(4)?;
                if (2..=MAX_SUB_RES).contains(&k) {
                    Ok(Policy::Constant(k))
                } else {
                    Err(format!("constant=k needs 2 ≤ k ≤ {MAX_SUB_RES}"))
                }
            }
            "max-depth" => Ok(Policy::MaxDepth { leaf_size: num(8)?.max(1) }),
            _ => {
                Err(format!("unknown policy \"{s}\": expected octree, max-depth[=leaf_size], constant[=k] or adaptive"))
            }
        }
    }
}

/// Multi-resolution build settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MultiresOptions {
    pub policy: Policy,
    /// Deepest sub-grid level (the top grid is depth 0); at most [`MAX_DEPTH`] − 1.
    pub max_depth: u32,
    /// Cells per triangle of an adaptive sub-grid.
    pub density: f64,
    pub cost: CostModel,
    /// Subdivide every non-empty cell, skipping the cost test (the two-level grid with
    /// [`crate::twolevel::TwoLevelOptions::every_cell`]).
    pub always_subdivide: bool,
}

impl Default for MultiresOptions {
    fn default() -> Self {
        MultiresOptions {
            policy: Policy::Adaptive,
            max_depth: 3,
            density: 0.5,
            cost: CostModel::default(),
            always_subdivide: false,
        }
    }
}

/// A built subtree with node/cell/ref indices local to it; node 0 is its root.
#[derive(Default)]
struct Subtree {
    nodes: Vec<Node>,
    cells: Vec<[u32; 2]>,
    refs: Vec<u32>,
}

impl Subtree {
    /// Appends `child`, rebasing its indices; returns the child's root node index.
    fn append(&mut self, child: Subtree) -> u32 {
        let (n0, c0, r0) = (self.nodes.len() as u32, self.cells.len() as u32, self.refs.len() as u32);
        self.nodes.extend(child.nodes.into_iter().map(|n| Node { first_cell: n.first_cell + c0, ..n }));
        self.cells.extend(child.cells.into_iter().map(|[a, b]| if b == CHILD { [a + n0, b] } else { [a + r0, b] }));
        self.refs.extend(child.refs);
        n0
    }
}

struct Ctx<'a> {
    tris: &'a [[Vec3; 3]],
    opts: MultiresOptions,
    insert: InsertMode,
    top_res: UVec3,
    /// Cells over all levels so far, kept or evaluated, held under `opts.cost.max_cells`.
    cells: std::sync::atomic::AtomicU64,
    /// References of every sub-grid so far, kept or evaluated, held under
    /// [`crate::build::MAX_REFS`] across the subtrees built in parallel.
    refs: std::sync::atomic::AtomicU64,
}

impl Ctx<'_> {
    /// Sub-grid resolution for a cell of extent `ext` holding `n` triangles.
    fn sub_res(&self, ext: Vec3, n: usize) -> UVec3 {
        let r = match self.opts.policy {
            Policy::Octree | Policy::MaxDepth { .. } => UVec3::splat(2),
            Policy::Constant(k) => UVec3::splat(k),
            Policy::Adaptive => {
                let v = ext.x as f64 * ext.y as f64 * ext.z as f64;
                let side = (v / (self.opts.density * n as f64).max(1.0)).cbrt();
                UVec3::from_array([0, 1, 2].map(|a| (ext[a] as f64 / side).round() as u32))
            }
        };
        r.clamp(UVec3::ONE, UVec3::splat(MAX_SUB_RES))
    }

    /// Builds the subtree for cell `c` of `parent` holding triangles `ids`, or `None` to keep
    /// it a leaf. The subtree holds at most `budget` references (at least `ids.len()`).
    fn subdivide(
        &self,
        parent: &GridGeometry,
        parent_scale: Vec3,
        c: UVec3,
        ids: &[u32],
        depth: u32,
        budget: f64,
    ) -> Result<Option<Subtree>, BuildError> {
        let n = ids.len();
        if n == 0 || depth > self.opts.max_depth.min(MAX_DEPTH as u32 - 1) {
            return Ok(None);
        }
        if let Policy::MaxDepth { leaf_size } = self.opts.policy
            && n <= leaf_size as usize
        {
            return Ok(None);
        }
        let res = self.sub_res(parent.cell, n);
        if res == UVec3::ONE {
            return Ok(None);
        }
        let scale = parent_scale * res.as_vec3();
        let geom = cell_geometry(parent, c, res);
        let margin = child_margin(self.top_res, scale, &geom, depth);
        if margin > MAX_CHILD_MARGIN {
            return Ok(None);
        }
        // Every candidate sub-grid counts, kept or not: bucketing one costs its cells, and a
        // huge density would otherwise evaluate (and reject) 64³ cells below every occupied cell.
        let used = self.cells.fetch_add(geom.cell_count(), std::sync::atomic::Ordering::Relaxed) + geom.cell_count();
        if used > self.opts.cost.max_cells {
            return Err(BuildError::TooManyCells { cells: used, limit: self.opts.cost.max_cells });
        }
        let cost_based = !matches!(self.opts.policy, Policy::MaxDepth { .. }) && !self.opts.always_subdivide;
        let m = self.opts.cost;
        let costlier = |refs: u64| cost_based && m.cost(geom.cell_count(), refs, n) >= n as f64 * m.t_inter;
        // Bounding-box insertion's references are counted from the boxes alone, so a sub-grid the
        // budget or the cost test rejects is never bucketed: needles whose boxes fill the cell
        // would land in every one of its cells (n times the cells, transiently). Exact insertion's
        // are known after the count: `bucket_within` stops there when they are over the budget.
        if self.insert == InsertMode::BoundingBox {
            let box_refs = box_references(self.tris, ids, &geom, margin);
            if box_refs as f64 > budget || costlier(box_refs) {
                return Ok(None);
            }
        }
        let Some((cell_start, refs)) =
            bucket_within(self.tris, Some(ids), &geom, self.insert, margin, budget as u64, None)?
        else {
            return Ok(None);
        };
        let n_refs = refs.len() as u64;
        crate::build::check_refs(self.refs.fetch_add(n_refs, std::sync::atomic::Ordering::Relaxed) + n_refs)?;
        if self.insert == InsertMode::Exact && costlier(n_refs) {
            return Ok(None);
        }
        // Each cell's share of the budget, in proportion to its references (never below them:
        // n_refs ≤ budget).
        let per_ref = budget / n_refs.max(1) as f64;
        let mut sub = Subtree::default();
        sub.nodes.push(Node { res, first_cell: 0, depth, margin: margin as f32, scale });
        sub.cells = crate::build::zeroed(geom.cell_count() as usize, "sub-grid cells")?;
        for z in 0..res.z {
            for y in 0..res.y {
                for x in 0..res.x {
                    let cc = UVec3::new(x, y, z);
                    let i = geom.cell_index(cc);
                    let cell_ids = &refs[cell_start[i] as usize..cell_start[i + 1] as usize];
                    let share = per_ref * cell_ids.len() as f64;
                    match self.subdivide(&geom, scale, cc, cell_ids, depth + 1, share)? {
                        Some(child) => {
                            let k = sub.append(child);
                            sub.cells[i] = [k, CHILD];
                        }
                        None => {
                            sub.cells[i] = [sub.refs.len() as u32, cell_ids.len() as u32];
                            sub.refs.extend_from_slice(cell_ids);
                        }
                    }
                    crate::build::check_refs(sub.refs.len() as u64)?;
                }
            }
        }
        Ok(Some(sub))
    }
}

/// Builds a multi-resolution grid whose top grid has resolution `top_res` over `bounds` (of
/// `tris`).
pub fn build(
    tris: &[[Vec3; 3]],
    bounds: &Aabb,
    top_res: [u32; 3],
    opts: MultiresOptions,
    build: BuildOptions,
    times: &mut PhaseTimes,
) -> Result<Hierarchy, BuildError> {
    if !(opts.density > 0.0 && opts.density.is_finite()) {
        return Err(BuildError::InvalidParameter(format!("density {} must be positive", opts.density)));
    }
    let geom = GridGeometry::new(bounds, top_res);
    crate::build::check_cells(geom.res.to_array(), opts.cost.max_cells)?;
    let top = FlatGrid::build(tris, geom, build, times)?;
    let ctx = Ctx {
        tris,
        opts,
        insert: build.insert,
        top_res: geom.res,
        cells: geom.cell_count().into(),
        refs: (top.refs.len() as u64).into(),
    };
    let cells = geom.cell_count() as usize;
    let one = |i: usize| -> Result<Option<Subtree>, BuildError> {
        let c = UVec3::new(
            i as u32 % geom.res.x,
            (i as u32 / geom.res.x) % geom.res.y,
            i as u32 / (geom.res.x * geom.res.y),
        );
        let ids = top.cell(i);
        ctx.subdivide(&geom, Vec3::ONE, c, ids, 1, SUBTREE_REFS_PER_TRIANGLE * ids.len() as f64)
    };
    let subtrees: Vec<Option<Subtree>> =
        times.record("subdivide", || -> Result<Vec<Option<Subtree>>, BuildError> {
            #[cfg(feature = "parallel")]
            if build.parallel {
                use rayon::prelude::*;
                return (0..cells).into_par_iter().map(one).collect();
            }
            (0..cells).map(one).collect()
        })?;
    let total: u64 = subtrees.iter().flatten().map(|s| s.refs.len() as u64).sum::<u64>() + top.refs.len() as u64;
    crate::build::check_refs(total)?;
    let parallel = build.parallel;
    let h = times.record("assemble", || assemble(geom, &top, &subtrees, parallel))?;
    Ok(h)
}

/// The hierarchy's compact arrays ([`Hierarchy::from_parts`]) written straight from the
/// top grid and its cells' subtrees: the top node, then each subtree's nodes in top-cell order;
/// the top grid's cells, then each subtree's; each cell's entries (a child's node index, or a
/// leaf's references) in the same order. Each subtree's part of the arrays is known from the
/// sizes before it, so the subtrees are written on all threads with `parallel`, and the result
/// is the serial one.
fn assemble(
    geom: GridGeometry,
    top: &FlatGrid,
    subtrees: &[Option<Subtree>],
    parallel: bool,
) -> Result<Hierarchy, BuildError> {
    use crate::hierarchy::CHILD_BIT;
    let top_cells = subtrees.len();
    let entries_of =
        |sub: &Subtree| -> u64 { sub.cells.iter().map(|&[_, b]| if b == CHILD { 1 } else { b as u64 }).sum() };
    let top_entries: u64 =
        (0..top_cells).map(|i| if subtrees[i].is_some() { 1 } else { top.cell(i).len() as u64 }).sum();
    let sub_entries: Vec<u64> = subtrees.iter().flatten().map(entries_of).collect();
    let entries = top_entries + sub_entries.iter().sum::<u64>();
    if entries >= CHILD_BIT as u64 {
        return Err(BuildError::TooManyReferences { refs: entries, limit: CHILD_BIT as u64 - 1 });
    }
    let pair_count = top_cells + subtrees.iter().flatten().map(|s| s.cells.len()).sum::<usize>();
    let mut nodes = Vec::with_capacity(1 + subtrees.iter().flatten().map(|s| s.nodes.len()).sum::<usize>());
    nodes.push(Node {
        res: geom.res,
        first_cell: 0,
        depth: 0,
        margin: crate::geometry::INSERT_MARGIN_CELLS as f32,
        scale: Vec3::ONE,
    });
    // Each subtree's first node, first cell and first entry.
    let mut bases = Vec::with_capacity(sub_entries.len());
    let (mut cell_base, mut entry_base) = (top_cells as u32, top_entries as u32);
    for (sub, &e) in subtrees.iter().flatten().zip(&sub_entries) {
        let node_base = nodes.len() as u32;
        nodes.extend(sub.nodes.iter().map(|n| Node { first_cell: n.first_cell + cell_base, ..*n }));
        bases.push((node_base, entry_base));
        cell_base += sub.cells.len() as u32;
        entry_base += e as u32;
    }
    let mut cells = crate::build::zeroed::<u32>(pair_count + 1, "hierarchy cells")?;
    let mut out = crate::build::zeroed::<u32>(entries as usize, "hierarchy references")?;
    // The top grid's cells.
    let (top_part, cells_rest) = cells.split_at_mut(top_cells);
    let (top_out, out_rest) = out.split_at_mut(top_entries as usize);
    let (mut at, mut k) = (0usize, 0usize);
    for (i, (cell, sub)) in top_part.iter_mut().zip(subtrees).enumerate() {
        if sub.is_some() {
            *cell = at as u32 | CHILD_BIT;
            top_out[at] = bases[k].0;
            at += 1;
            k += 1;
        } else {
            let ids = top.cell(i);
            *cell = at as u32;
            top_out[at..at + ids.len()].copy_from_slice(ids);
            at += ids.len();
        }
    }
    // Each subtree's cells and entries, in parts of their own.
    let cell_parts = split_lengths(cells_rest, subtrees.iter().flatten().map(|s| s.cells.len()));
    let out_parts = split_lengths(out_rest, sub_entries.iter().map(|&e| e as usize));
    let parts: Vec<_> = subtrees
        .iter()
        .flatten()
        .zip(cell_parts)
        .zip(out_parts)
        .zip(&bases)
        .map(|(((sub, c), o), &(node_base, entry_base))| (sub, c, o, node_base, entry_base))
        .collect();
    let write = |(sub, c, o, node_base, entry_base): (&Subtree, &mut [u32], &mut [u32], u32, u32)| {
        let mut at = 0usize;
        for (cell, &[a, b]) in c.iter_mut().zip(&sub.cells) {
            if b == CHILD {
                *cell = (entry_base + at as u32) | CHILD_BIT;
                o[at] = node_base + a;
                at += 1;
            } else {
                *cell = entry_base + at as u32;
                o[at..at + b as usize].copy_from_slice(&sub.refs[a as usize..(a + b) as usize]);
                at += b as usize;
            }
        }
    };
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        parts.into_par_iter().for_each(write);
    } else {
        parts.into_iter().for_each(write);
    }
    #[cfg(not(feature = "parallel"))]
    {
        let _ = parallel;
        parts.into_iter().for_each(write);
    }
    cells[pair_count] = entries as u32;
    Ok(Hierarchy::from_parts(geom, nodes, cells, out))
}
