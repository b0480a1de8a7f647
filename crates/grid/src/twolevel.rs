//! Two-level grids (Kalojanov, Billeter & Slusallek 2011): a top grid at low density, and a
//! non-empty top cell its own leaf grid, with a resolution from its own triangle count.
//!
//! Densities are theirs: top density λ₁ = 1/16 cells per triangle, leaf density λ₂ = 1.2. It is
//! the multi-resolution structure with depth 1 and adaptive leaf resolution, so it shares its
//! builder ([`crate::multires`]) and its compact layout and traversal ([`crate::hierarchy`]): top
//! cell → leaf grid → leaf cell → reference range.
//!
//! Their rule gives every non-empty top cell a leaf grid ([`TwoLevelOptions::every_cell`]). By
//! default the survey's cost test decides instead, as in the multi-resolution grid: a top cell
//! keeps its triangle list when its leaf grid is predicted costlier than testing the list. With
//! bounding-box insertion the every-cell rule grows with the square of a top cell's triangles
//! when their boxes fill it (needles, hair, wires: each of n triangles lands in all of the leaf
//! grid's ~λ₂·n cells), and the cost test rejects exactly those leaf grids.

use glam::Vec3;
use gridrt_scene::Aabb;
use serde::{Deserialize, Serialize};

use crate::BuildError;
use crate::build::{BuildOptions, PhaseTimes};
use crate::hierarchy::Hierarchy;
use crate::multires::{MultiresOptions, Policy};
use crate::resolution::{CostModel, cubic_cells};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TwoLevelOptions {
    /// Top-grid cells per triangle (λ₁).
    pub top_density: f64,
    /// Leaf-grid cells per triangle of each top cell (λ₂).
    pub leaf_density: f64,
    /// Kalojanov et al.'s rule: a leaf grid under every non-empty top cell, without the cost
    /// test (module doc).
    #[serde(default)]
    pub every_cell: bool,
}

impl Default for TwoLevelOptions {
    fn default() -> Self {
        TwoLevelOptions { top_density: 1.0 / 16.0, leaf_density: 1.2, every_cell: false }
    }
}

/// The top resolution the two-level grid uses for `triangles` triangles in `bounds` (λ₁·N
/// cells, near-cubic).
pub fn top_resolution(bounds: &Aabb, triangles: usize, opts: &TwoLevelOptions) -> [u32; 3] {
    cubic_cells(bounds, opts.top_density * triangles as f64)
}

/// Builds a two-level grid over `bounds` (of `tris`); `top_res = None` uses [`top_resolution`].
/// `cost` is the cost model of the leaf grids' test; its `max_cells` bounds the cells of both
/// levels together.
pub fn build(
    tris: &[[Vec3; 3]],
    bounds: &Aabb,
    top_res: Option<[u32; 3]>,
    opts: TwoLevelOptions,
    build: BuildOptions,
    cost: CostModel,
    times: &mut PhaseTimes,
) -> Result<Hierarchy, BuildError> {
    let ok = |d: f64| d > 0.0 && d.is_finite();
    if !(ok(opts.top_density) && ok(opts.leaf_density)) {
        return Err(BuildError::InvalidParameter(format!(
            "two-level densities must be positive and finite (top {}, leaf {})",
            opts.top_density, opts.leaf_density
        )));
    }
    let top = top_res.unwrap_or_else(|| top_resolution(bounds, tris.len(), &opts));
    let m = MultiresOptions {
        policy: Policy::Adaptive,
        max_depth: 1,
        density: opts.leaf_density,
        cost,
        always_subdivide: opts.every_cell,
    };
    crate::multires::build(tris, bounds, top, m, build, times)
}
