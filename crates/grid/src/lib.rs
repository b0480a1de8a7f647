//! CPU grid acceleration structures for gridrt (pure Rust; compiles for wasm32 with the
//! `parallel` feature off).
//!
//! Data flows one way: triangles → [`resolution`] (choose the grid size) → a structure
//! ([`flat`], [`macrocell`], [`multires`], [`twolevel`], [`proximity`]; built with [`insert`],
//! hierarchies laid out by [`hierarchy`]) → closest hit ([`trace`], walking cells with a
//! [`traversal`]; packets of coherent rays slice by slice with [`coherent`]) → hits and [`stats`]. [`structure`] is the one entry point over all kinds;
//! [`brute`] is the reference every structure must reproduce bit for bit.

pub mod brute;
pub mod build;
pub mod cell_plane;
pub mod coherent;
pub mod flat;
pub mod geometry;
pub mod hierarchy;
pub mod insert;
pub mod irregular;
pub mod macrocell;
pub mod mailbox;
pub mod multires;
pub mod proximity;
pub mod ray;
pub mod resolution;
pub mod stats;
pub mod structure;
pub mod trace;
pub mod traversal;
pub mod triangle;
pub mod twolevel;

use glam::Vec3;
use gridrt_scene::Aabb;
use thiserror::Error;

pub use build::{BuildOptions, BuildScratch, PhaseTimes, check_cells};
pub use coherent::{PacketOptions, PacketStats};
pub use flat::{FlatGrid, OccupancyWord};
pub use geometry::GridGeometry;
pub use insert::InsertMode;
pub use resolution::{CostModel, Resolution, ResolutionChoice};
pub use stats::{BatchStats, HierarchyStats, RayStats, StructureStats};
pub use structure::{AnyGrid, BuildReport, GridConfig, GridKind};
pub use trace::{Query, TraceOptions};
pub use traversal::Traversal;

#[derive(Debug, Error, PartialEq)]
pub enum BuildError {
    #[error("{0} triangles: a grid indexes at most 2^32 - 2")]
    TooManyTriangles(u64),
    #[error(
        "the grid would hold at least {refs} triangle references, more than the limit of {limit}; lower the resolution or use exact insertion (--exact)"
    )]
    TooManyReferences { refs: u64, limit: u64 },
    #[error(
        "the grid would have {cells} cells, more than the limit of {limit}; lower the resolution or raise the cell limit (--max-cells)"
    )]
    TooManyCells { cells: u64, limit: u64 },
    #[error("cannot allocate {what} ({bytes} bytes): out of memory")]
    OutOfMemory { what: &'static str, bytes: u64 },
    #[error("{0}")]
    InvalidParameter(String),
}

/// Bounds of a triangle soup (all corners).
pub fn triangle_bounds(tris: &[[Vec3; 3]]) -> Aabb {
    triangle_bounds_with(tris, false)
}

/// [`triangle_bounds`] and, for each run of [`resolution::COUNT_CHUNK`] triangles, its widest
/// triangle extent per axis, in one pass (on all threads when `parallel`): guess-and-check then
/// skips reading the runs whose triangles are all narrower than a cell (see
/// [`resolution::count_refs_curve_with`]).
pub fn triangle_bounds_and_extents(tris: &[[Vec3; 3]], parallel: bool) -> (Aabb, resolution::ChunkExtents) {
    let one = Aabb::of_triangles_and_widest;
    #[cfg(feature = "parallel")]
    let parts: Vec<(Aabb, Vec3)> = if parallel {
        use rayon::prelude::*;
        tris.par_chunks(resolution::COUNT_CHUNK).map(one).collect()
    } else {
        tris.chunks(resolution::COUNT_CHUNK).map(one).collect()
    };
    #[cfg(not(feature = "parallel"))]
    let parts: Vec<(Aabb, Vec3)> = {
        let _ = parallel;
        tris.chunks(resolution::COUNT_CHUNK).map(one).collect()
    };
    let bounds = parts.iter().fold(Aabb::EMPTY, |a, (b, _)| a.union(b));
    (bounds, resolution::ChunkExtents(parts.into_iter().map(|(_, w)| w).collect()))
}

/// [`triangle_bounds`], on all threads when `parallel` (and the `parallel` feature) is on.
/// Min and max are exact, so the result does not depend on the split.
pub fn triangle_bounds_with(tris: &[[Vec3; 3]], parallel: bool) -> Aabb {
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        return tris.par_chunks(16 * 1024).map(Aabb::of_triangles).reduce(|| Aabb::EMPTY, |a, b| a.union(&b));
    }
    let _ = parallel;
    Aabb::of_triangles(tris)
}

/// Chooses the resolution and builds a flat grid: [`structure::build`] for [`GridKind::Flat`],
/// with the grid and its resolution choice unpacked. Phase times: `bounds`, `resolution`, then
/// the build's own phases.
pub fn build_flat(
    tris: &[[Vec3; 3]],
    policy: Resolution,
    model: &CostModel,
    opts: BuildOptions,
) -> Result<(FlatGrid, ResolutionChoice, PhaseTimes), BuildError> {
    let cfg = GridConfig {
        kind: GridKind::Flat,
        resolution: Some(policy),
        build: opts,
        cost: *model,
        ..GridConfig::default()
    };
    let (grid, report) = structure::build(tris, &cfg)?;
    let AnyGrid::Flat(grid) = grid else { unreachable!("structure::build returns the kind it is asked for") };
    let choice = report.resolution_choice.expect("a flat grid always chooses a resolution");
    Ok((grid, choice, report.times))
}
