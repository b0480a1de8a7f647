//! Irregular grids (Pérard-Gayot, Kalojanov & Slusallek, "GPU Ray Tracing using Irregular
//! Grids", 2017; the model codebase is hagrid): a flat grid's cells merged into boxes of many
//! voxels where that lowers the surface-area cost, each box then expanded over its neighbours
//! as far as they hold no triangle it lacks. A ray looks up the box of the voxel it is in,
//! tests the box's triangles and jumps to where it leaves the (expanded) box: far fewer steps
//! than one per voxel, in empty space and along surfaces alike.
//!
//! Experimental: not yet a [`crate::GridKind`] (no CLI, app or GPU path); the README's levers
//! table has its measurements and what it lacks (a compact voxel map, a fast build).
//!
//! Exactness: a box's references are the union of its voxels' references, and an expanded box
//! covers only voxels whose references are a subset of its own. So every triangle the ray can
//! hit inside a visited box (within the insertion margin, see [`crate::geometry`]) is among
//! the box's references, and the closest-hit rule's "done once the best hit lies before the
//! exit" holds as in the flat grid.
//!
//! # Layout
//! `voxel_cell`: a u32 per voxel of the underlying flat grid (x fastest), the index of its
//! cell; `cells`: per cell its expanded voxel box and its run of `refs` (increasing triangle
//! order).

use glam::{UVec3, Vec3};
use gridrt_scene::{Hit, Ray};

use crate::flat::FlatGrid;
use crate::geometry::{GridGeometry, linear_index};
use crate::stats::RayStats;
use crate::trace::TraceOptions;
use crate::trace::closest_hit::closest_hit;

/// One cell of an irregular grid: a box of voxels `[min, max)` (after expansion) and its
/// triangles `refs[start..end]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct IrregularCell {
    pub min: [u16; 3],
    pub max: [u16; 3],
    pub start: u32,
    pub end: u32,
}

/// How the cells are merged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrregularOptions {
    /// The cost of a step relative to a triangle test, in the merge's surface-area cost
    /// `area × (refs + step_cost)`.
    pub step_cost: f32,
    /// Merge rounds (x, y, z each) at most; merging stops earlier once a round removes fewer
    /// than 1% of the cells.
    pub max_rounds: u32,
    /// Whether cells are expanded over their neighbours after merging.
    pub expand: bool,
}

impl Default for IrregularOptions {
    fn default() -> Self {
        IrregularOptions { step_cost: 1.0, max_rounds: 12, expand: true }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct IrregularGrid {
    /// The voxel grid the cells are made of.
    pub geom: GridGeometry,
    /// Per voxel, the index of the cell that owns it.
    pub voxel_cell: Vec<u32>,
    pub cells: Vec<IrregularCell>,
    pub refs: Vec<u32>,
}

/// Half the surface area of a box of `e` (world units): the merge's cost weight.
fn half_area(e: Vec3) -> f32 {
    e.x * (e.y + e.z) + e.y * e.z
}

/// Elements in the union of two increasing lists.
fn union_len(a: &[u32], b: &[u32]) -> usize {
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < a.len() && j < b.len() {
        let (x, y) = (a[i], b[j]);
        i += (x <= y) as usize;
        j += (x >= y) as usize;
        n += 1;
    }
    n + (a.len() - i) + (b.len() - j)
}

/// Appends the union of two increasing lists to `out`.
fn union_into(a: &[u32], b: &[u32], out: &mut Vec<u32>) {
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        let (x, y) = (a[i], b[j]);
        out.push(x.min(y));
        i += (x <= y) as usize;
        j += (x >= y) as usize;
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
}

/// Whether the increasing list `sub` is a subset of the increasing list `of`.
fn is_subset(sub: &[u32], of: &[u32]) -> bool {
    if sub.len() > of.len() {
        return false;
    }
    let mut j = 0;
    for &x in sub {
        while j < of.len() && of[j] < x {
            j += 1;
        }
        if j == of.len() || of[j] != x {
            return false;
        }
        j += 1;
    }
    true
}

impl IrregularGrid {
    /// Merges and expands the cells of `grid`.
    pub fn from_flat(grid: &FlatGrid, opts: IrregularOptions) -> IrregularGrid {
        let geom = grid.geom;
        let res = geom.res;
        let voxels = geom.cell_count() as usize;
        // One cell per voxel to start with.
        let mut cells = Vec::with_capacity(voxels);
        let mut refs = Vec::with_capacity(grid.refs.len());
        for z in 0..res.z {
            for y in 0..res.y {
                for x in 0..res.x {
                    let v = UVec3::new(x, y, z);
                    let start = refs.len() as u32;
                    refs.extend_from_slice(grid.cell(linear_index(v, res)));
                    let min = [x as u16, y as u16, z as u16];
                    let max = [x as u16 + 1, y as u16 + 1, z as u16 + 1];
                    cells.push(IrregularCell { min, max, start, end: refs.len() as u32 });
                }
            }
        }
        let mut g = IrregularGrid { geom, voxel_cell: (0..voxels as u32).collect(), cells, refs };
        for _ in 0..opts.max_rounds {
            let before = g.cells.len();
            for axis in 0..3 {
                g.merge_pass(axis, opts.step_cost);
            }
            if g.cells.len() * 100 > before * 99 {
                break;
            }
        }
        if opts.expand {
            g.expand();
        }
        g
    }

    fn cell_refs(&self, c: &IrregularCell) -> &[u32] {
        &self.refs[c.start as usize..c.end as usize]
    }

    /// One merge pass along `axis`: each cell merges with its neighbour across its upper face
    /// when both have the same extent on the other axes and the merged cell costs no more
    /// than the two (`area × (refs + step_cost)`). Cells are in increasing order of their
    /// lowest voxel, so a row of mergeable cells merges in pairs.
    fn merge_pass(&mut self, axis: usize, step_cost: f32) {
        let res = self.geom.res;
        let size = self.geom.cell;
        let extent = |c: &IrregularCell| Vec3::from_array(std::array::from_fn(|a| (c.max[a] - c.min[a]) as f32)) * size;
        const NONE: u32 = u32::MAX;
        let mut new_id = vec![NONE; self.cells.len()];
        let mut cells = Vec::with_capacity(self.cells.len());
        let mut refs = Vec::with_capacity(self.refs.len());
        for id in 0..self.cells.len() {
            if new_id[id] != NONE {
                continue;
            }
            let c = self.cells[id];
            let mut partner = None;
            if (c.max[axis] as u32) < res[axis] {
                let mut v = c.min;
                v[axis] = c.max[axis];
                let nid = self.voxel_cell[linear_index(UVec3::from_array(v.map(u32::from)), res)] as usize;
                let n = self.cells[nid];
                let aligned = (0..3).all(|a| a == axis || (n.min[a] == c.min[a] && n.max[a] == c.max[a]));
                if aligned && n.min[axis] == c.max[axis] {
                    let (rc, rn) = (self.cell_refs(&c), self.cell_refs(&n));
                    let (ec, en) = (extent(&c), extent(&n));
                    let mut em = ec;
                    em[axis] += en[axis];
                    let split =
                        half_area(ec) * (rc.len() as f32 + step_cost) + half_area(en) * (rn.len() as f32 + step_cost);
                    let merged = |n: usize| half_area(em) * (n as f32 + step_cost);
                    // The larger list is a lower bound of the union: a cheap reject first.
                    if merged(rc.len().max(rn.len())) <= split && merged(union_len(rc, rn)) <= split {
                        partner = Some(nid);
                    }
                }
            }
            let start = refs.len() as u32;
            let mut cell = c;
            match partner {
                Some(nid) => {
                    let n = self.cells[nid];
                    union_into(self.cell_refs(&c), self.cell_refs(&n), &mut refs);
                    cell.max[axis] = n.max[axis];
                    new_id[nid] = cells.len() as u32;
                }
                None => refs.extend_from_slice(self.cell_refs(&c)),
            }
            new_id[id] = cells.len() as u32;
            cell.start = start;
            cell.end = refs.len() as u32;
            cells.push(cell);
        }
        for v in &mut self.voxel_cell {
            *v = new_id[*v as usize];
        }
        self.cells = cells;
        self.refs = refs;
    }

    /// Grows every cell's box, face by face (x−, x+, y−, y+, z−, z+), a layer of voxels at a
    /// time while every voxel of the layer belongs to a cell whose references are a subset of
    /// this cell's. Neighbours are judged by their own (unexpanded) voxels, so the order in
    /// which cells grow does not matter.
    fn expand(&mut self) {
        let res = self.geom.res;
        let mut boxes: Vec<([u16; 3], [u16; 3])> = Vec::with_capacity(self.cells.len());
        for c in &self.cells {
            let own = self.cell_refs(c);
            let (mut lo, mut hi) = (c.min, c.max);
            for axis in 0..3 {
                for up in [false, true] {
                    loop {
                        let layer = if up { hi[axis] as u32 } else { lo[axis] as u32 };
                        if (up && layer >= res[axis]) || (!up && layer == 0) {
                            break;
                        }
                        let layer = if up { layer } else { layer - 1 };
                        if !self.layer_within(own, axis, layer, lo, hi) {
                            break;
                        }
                        if up {
                            hi[axis] += 1;
                        } else {
                            lo[axis] -= 1;
                        }
                    }
                }
            }
            boxes.push((lo, hi));
        }
        for (c, (lo, hi)) in self.cells.iter_mut().zip(boxes) {
            c.min = lo;
            c.max = hi;
        }
    }

    /// Whether every voxel of layer `layer` on `axis`, over `[lo, hi)` on the other axes,
    /// belongs to a cell whose references are a subset of `own`.
    fn layer_within(&self, own: &[u32], axis: usize, layer: u32, lo: [u16; 3], hi: [u16; 3]) -> bool {
        let res = self.geom.res;
        let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut last = u32::MAX;
        for j in lo[a2]..hi[a2] {
            for i in lo[a1]..hi[a1] {
                let mut v = UVec3::ZERO;
                v[axis] = layer;
                v[a1] = i as u32;
                v[a2] = j as u32;
                let id = self.voxel_cell[linear_index(v, res)];
                if id == last {
                    continue;
                }
                last = id;
                let n = &self.cells[id as usize];
                if n.start != n.end && !is_subset(self.cell_refs(n), own) {
                    return false;
                }
            }
        }
        true
    }

    /// Bytes of the voxel map, the cells and the references.
    pub fn memory_bytes(&self) -> u64 {
        (self.voxel_cell.len() * 4 + self.cells.len() * size_of::<IrregularCell>() + self.refs.len() * 4) as u64
    }

    /// Closest hit: from cell to cell, each left at its box's exit.
    pub fn trace(&self, tris: &[[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> (Hit, RayStats) {
        closest_hit(tris, ray, opts, |search| {
            let Some(gr) = self.geom.clip(&search.ray) else { return };
            let res = self.geom.res;
            let up = gr.d.cmpgt(Vec3::ZERO);
            let mut voxel = gr.start_cell(res);
            loop {
                let c = &self.cells[self.voxel_cell[linear_index(voxel, res)] as usize];
                // The far planes of the box, per axis (∞ on axes the ray does not move along).
                let mut t_axis = [f32::INFINITY; 3];
                let mut t_exit = gr.t1;
                for (a, t) in t_axis.iter_mut().enumerate() {
                    if gr.d[a] != 0.0 {
                        let plane = if up.test(a) { c.max[a] } else { c.min[a] } as f32;
                        *t = (plane - gr.o[a]) * gr.inv_d[a];
                        t_exit = t_exit.min(*t);
                    }
                }
                search.visit_cell();
                let done = if c.start != c.end {
                    search.test_cell(&self.refs[c.start as usize..c.end as usize], t_exit)
                } else {
                    search.done_at(t_exit)
                };
                if done || t_exit >= gr.t1 {
                    return;
                }
                // The next voxel: across the exit plane(s), elsewhere where the ray is at the
                // exit (never behind the current voxel).
                let p = gr.o + gr.d * t_exit;
                let at = p.clamp(Vec3::ZERO, (res - UVec3::ONE).as_vec3()).as_uvec3();
                for a in 0..3 {
                    if gr.d[a] == 0.0 {
                        continue;
                    }
                    if t_axis[a] == t_exit {
                        if up.test(a) {
                            if c.max[a] as u32 >= res[a] {
                                return;
                            }
                            voxel[a] = c.max[a] as u32;
                        } else {
                            if c.min[a] == 0 {
                                return;
                            }
                            voxel[a] = c.min[a] as u32 - 1;
                        }
                    } else if up.test(a) {
                        voxel[a] = voxel[a].max(at[a]);
                    } else {
                        voxel[a] = voxel[a].min(at[a]);
                    }
                }
            }
        })
    }
}
