//! The layout and traversal shared by the hierarchical grids ([`crate::multires`],
//! [`crate::twolevel`]): a tree of uniform grids in flat arrays.
//!
//! # Layout (GPU-ready: flat arrays, indices only)
//! - `nodes`: one [`Node`] per grid: its resolution, the index of its first cell in `cells`,
//!   its depth. Node 0 is the top grid; its box is the structure's box. A child node fills
//!   exactly one cell of its parent, so its box is implied by the path and never stored.
//! - `cells`: one u32 per cell, plus one at the end: where the cell's entries start in `refs`,
//!   with [`CHILD_BIT`] set for an internal cell. All cells, of all nodes, own consecutive
//!   ranges of `refs` in cell order, so a leaf's range ends where the next entry's starts (the
//!   compact layout of the flat grid, Lagae & Dutré, over the whole tree); an internal cell
//!   owns one entry, its child node's index.
//! - `refs`: triangle indices, increasing within each leaf, and the child indices.
//!
//! Why a flat node array and not the survey's hash table of internal voxels: every cell needs
//! its slot anyway when it is a leaf, so the child index costs one entry of `refs` per
//! internal cell, found in O(1) without probing. A hash table keyed by (node, cell) would add
//! ≥ 8 bytes per internal voxel (key + value, more with a load factor below 1), and probe
//! sequences on the GPU. Measured memory per structure is printed by `gridrt build --json`.
//!
//! # Traversal
//! A stack of walkers, one per level: each cell of the current grid is either a leaf (test its
//! triangles) or a child grid, walked over that cell's `[t_enter, t_exit]` ([`GridRay::child`],
//! which clamps rather than clips, so a cell the parent grazes within the margin is still
//! searched). The closest-hit rule is the flat grid's, applied at every level: stop at
//! the first visited leaf whose exit `t` lies beyond the best hit.
//!
//! # Robustness
//! A child grid's ray is derived from its parent's, so rounding errors grow with the product of
//! the resolutions along the path. Each node therefore inserts with its own margin
//! ([`Node::margin`]), at least [`INSERT_MARGIN_CELLS`] and never smaller than a bound on that
//! error; the builders refuse to subdivide where the margin would exceed
//! [`MAX_CHILD_MARGIN`] of a cell (f32 has run out of precision there).

use glam::{UVec3, Vec3};
use gridrt_scene::{Hit, Ray};
use serde::{Deserialize, Serialize};

use crate::geometry::{GridGeometry, GridRay, INSERT_MARGIN_CELLS};
use crate::stats::RayStats;
use crate::stats::{HierarchyStats, StructureStats};
use crate::trace::TraceOptions;
use crate::trace::closest_hit::ClosestHit;
use crate::trace::closest_hit::closest_hit;
use crate::traversal::{Traversal, walk_counted};

/// The builders' cell pairs: `[node, CHILD]` marks an internal cell, `[start, count]` a leaf
/// (`multires::assemble` lays them out compactly: [`Hierarchy::from_parts`]).
pub const CHILD: u32 = u32::MAX;
/// Set in a cell's entry of [`Hierarchy::cells`] when the cell is a child grid.
pub const CHILD_BIT: u32 = 1 << 31;
/// Deepest level any hierarchy may have (the traversal stack is this deep).
pub const MAX_DEPTH: usize = 8;
/// Largest insertion margin, in cells, a child grid may need before subdividing is refused.
pub const MAX_CHILD_MARGIN: f64 = 0.125;

/// One grid of the hierarchy.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Node {
    pub res: UVec3,
    pub first_cell: u32,
    pub depth: u32,
    /// Insertion margin of this node's cells, in cells.
    pub margin: f32,
    /// Product of the resolutions on the path from the top grid, per axis: one of this node's
    /// cells is `1/scale` of a top-grid cell.
    pub scale: Vec3,
}

/// A hierarchy of uniform grids (see the module doc).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hierarchy {
    /// The top grid's box and resolution.
    pub geom: GridGeometry,
    pub nodes: Vec<Node>,
    pub cells: Vec<u32>,
    pub refs: Vec<u32>,
}

/// What one cell of a hierarchy holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Cell {
    /// Triangles `refs[range]`.
    Leaf(std::ops::Range<usize>),
    /// A child grid: the node's index.
    Child(u32),
}

/// The margin (in cells) a node `geom` at `depth` with accumulated `scale` needs. The ray's side:
/// f32 coordinates of the top grid (up to its resolution) carry a relative error of a few ulps,
/// magnified by `scale` in child cells. The triangles' side: the node's box is found in world
/// coordinates, one rounding per level ([`cell_geometry`]), and a corner is mapped into it by one
/// more, each up to an ulp of the coordinates' magnitude, which far from the origin can be a
/// good part of a deep node's cell (a scene at 3e6 has ulps of 0.25).
pub fn child_margin(top_res: UVec3, scale: Vec3, geom: &GridGeometry, depth: u32) -> f64 {
    let ray = 16.0 * f32::EPSILON as f64 * top_res.max_element() as f64 * scale.max_element() as f64;
    let magnitude = geom.min.abs().max(geom.max.abs()).max_element() as f64;
    let world = 4.0 * (depth as f64 + 2.0) * f32::EPSILON as f64 * magnitude / geom.cell.min_element() as f64;
    ray.max(world).max(INSERT_MARGIN_CELLS)
}

impl Hierarchy {
    /// A hierarchy from its compact arrays (the multires build writes them,
    /// `multires::assemble`): per cell in node order an offset into `refs`, with [`CHILD_BIT`]
    /// set for a child grid, and one more offset at the end; at a leaf's offset its references,
    /// at a child's its node index.
    pub(crate) fn from_parts(geom: GridGeometry, nodes: Vec<Node>, cells: Vec<u32>, refs: Vec<u32>) -> Hierarchy {
        Hierarchy { geom, nodes, cells, refs }
    }

    /// What cell `i` (an index into `cells`, node offset included) holds.
    #[inline]
    pub fn cell(&self, i: usize) -> Cell {
        let start = (self.cells[i] & !CHILD_BIT) as usize;
        if self.cells[i] & CHILD_BIT != 0 {
            Cell::Child(self.refs[start])
        } else {
            Cell::Leaf(start..(self.cells[i + 1] & !CHILD_BIT) as usize)
        }
    }

    pub fn memory_bytes(&self) -> u64 {
        (self.nodes.len() * std::mem::size_of::<Node>() + self.cells.len() * 4 + self.refs.len() * 4) as u64
    }

    /// Size figures: nodes per depth in `depth_histogram`, empty leaves in `empty_cells`.
    pub fn stats(&self, triangles: usize) -> StructureStats {
        let mut s = StructureStats {
            resolution: self.geom.res.to_array(),
            nodes: self.nodes.len() as u64,
            cells: self.cells.len() as u64,
            refs: self.refs.len() as u64,
            ..StructureStats::sized(self.memory_bytes(), triangles)
        };
        let mut h = HierarchyStats::default();
        for n in &self.nodes {
            let d = n.depth as usize;
            if s.depth_histogram.len() <= d {
                s.depth_histogram.resize(d + 1, 0);
                h.refs_per_depth.resize(d + 1, 0);
            }
            s.depth_histogram[d] += 1;
            let count = (n.res.x * n.res.y * n.res.z) as usize;
            for i in n.first_cell as usize..n.first_cell as usize + count {
                if let Cell::Leaf(r) = self.cell(i) {
                    h.leaves += 1;
                    s.empty_cells += r.is_empty() as u64;
                    h.refs_per_depth[d] += r.len() as u64;
                }
            }
        }
        s.levels = s.depth_histogram.len() as u32;
        s.hierarchy = Some(h);
        s
    }

    /// Closest hit (see the module doc).
    pub fn trace(&self, tris: &[[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> (Hit, RayStats) {
        let traversal = opts.traversal;
        closest_hit(tris, ray, opts, |search| {
            if let Some(top) = self.geom.clip(&search.ray) {
                self.walk_node(0, &top, traversal, search);
            }
        })
    }

    /// Walks node `n` along `ray` (clipped to the node), descending into child grids; true when
    /// the search is done. Recursion depth is the hierarchy's, at most [`MAX_DEPTH`].
    fn walk_node(&self, n: u32, ray: &GridRay, traversal: Traversal, search: &mut ClosestHit) -> bool {
        let node = &self.nodes[n as usize];
        let mut t_enter = ray.t0;
        let (done, cells) = walk_counted(traversal, ray, node.res, |cell, addr, t_exit| {
            let entered = std::mem::replace(&mut t_enter, t_exit);
            // Empty leaves (most cells) are checked in the walk's loop; tests and descents are
            // calls, which keeps that loop small enough to be compiled into the walk.
            match self.cell(node.first_cell as usize + addr) {
                Cell::Child(a) => self.descend(a, ray, cell, entered, t_exit, traversal, search),
                Cell::Leaf(r) if r.is_empty() => search.done_at(t_exit),
                Cell::Leaf(r) => self.test_leaf(search, r, t_exit),
            }
        });
        search.visit_cells(cells);
        done
    }

    /// Walks child node `a`, which fills `cell` of the grid `ray` walks, over `[entered, t_exit]`.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn descend(
        &self,
        a: u32,
        ray: &GridRay,
        cell: UVec3,
        entered: f32,
        t_exit: f32,
        traversal: Traversal,
        search: &mut ClosestHit,
    ) -> bool {
        let r = ray.child(cell, self.nodes[a as usize].res, entered, t_exit);
        self.walk_node(a, &r, traversal, search)
    }

    #[inline(never)]
    fn test_leaf(&self, search: &mut ClosestHit, r: std::ops::Range<usize>, t_exit: f32) -> bool {
        search.test_cell(&self.refs[r], t_exit)
    }
}

/// The grid geometry of the cell `c` of a grid `parent`, subdivided into `res` cells.
pub fn cell_geometry(parent: &GridGeometry, c: UVec3, res: UVec3) -> GridGeometry {
    let min = parent.min + c.as_vec3() * parent.cell;
    let cell = parent.cell / res.as_vec3();
    GridGeometry { min, max: min + parent.cell, res, cell, inv_cell: Vec3::ONE / cell }
}
