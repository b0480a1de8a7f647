//! One front door to every grid structure: pick a [`GridKind`] and its options, build, trace,
//! report. The CLI, the GPU crate and the app all go through here.

use glam::Vec3;
use gridrt_scene::{Hit, Ray};
use serde::{Deserialize, Serialize};

use crate::build::{BuildOptions, BuildScratch, PhaseTimes};
use crate::cell_plane::{self, CellPlanes};
use crate::coherent::{self, PacketOptions, PacketStats};
use crate::flat::FlatGrid;
use crate::geometry::GridGeometry;
use crate::hierarchy::Hierarchy;
use crate::insert::InsertMode;
use crate::macrocell::{MacroSample, MacrocellGrid};
use crate::multires::MultiresOptions;
use crate::proximity::ProximityGrid;
use crate::resolution::{self, CostModel, Resolution, ResolutionChoice};
use crate::stats::{BatchStats, RayStats, StructureStats};
use crate::trace::interleaved;
use crate::trace::{TraceOptions, trace_batch, trace_chunks, trace_flat};
use crate::traversal::Traversal;
use crate::twolevel::TwoLevelOptions;
use crate::{BuildError, triangle_bounds_and_extents};

/// The structures (`--grid`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum GridKind {
    #[default]
    Flat,
    Macrocell,
    Multires,
    TwoLevel,
    Proximity,
}

impl GridKind {
    pub const ALL: [GridKind; 5] =
        [GridKind::Flat, GridKind::Macrocell, GridKind::Multires, GridKind::TwoLevel, GridKind::Proximity];

    pub fn name(self) -> &'static str {
        match self {
            GridKind::Flat => "flat",
            GridKind::Macrocell => "macrocell",
            GridKind::Multires => "multires",
            GridKind::TwoLevel => "twolevel",
            GridKind::Proximity => "proximity",
        }
    }
}

impl std::str::FromStr for GridKind {
    type Err = String;
    fn from_str(s: &str) -> Result<GridKind, String> {
        GridKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown grid \"{s}\": expected flat, macrocell, multires, twolevel or proximity"))
    }
}

impl std::fmt::Display for GridKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The multi-resolution grid's default top grid: coarse (λ = 1/16 cell per triangle), since
/// subdivision refines where the triangles are (Jevans & Wyvill build top-down from coarse).
/// Measured on Sponza and the teapot in a stadium, a top grid at the flat grid's auto
/// resolution used 1.5–3× the memory for no fewer cells per ray; 1/16 with adaptive
/// sub-grids of λ = 0.5 gave the fewest cells + tests per ray at less memory than the flat grid.
pub const MULTIRES_TOP_DEFAULT: Resolution = Resolution::Density(0.0625);

/// Everything that decides how a structure is built.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridConfig {
    pub kind: GridKind,
    /// Resolution of the flat grid / the fine grid of macrocells / the top grid of the
    /// hierarchies. `None`: each kind's default (auto; multires [`MULTIRES_TOP_DEFAULT`];
    /// two-level λ₁·N).
    pub resolution: Option<Resolution>,
    pub build: BuildOptions,
    pub cost: CostModel,
    /// Macrocell edge in fine cells (power of two); `None`: chosen by the cost model.
    pub macro_size: Option<u32>,
    pub multires: MultiresOptions,
    pub twolevel: TwoLevelOptions,
    /// Which flat and macrocell grids get cell slabs ([`crate::cell_plane`]).
    #[serde(default)]
    pub cell_planes: CellPlanes,
}

impl Default for GridConfig {
    fn default() -> Self {
        GridConfig {
            kind: GridKind::Flat,
            resolution: None,
            build: BuildOptions { insert: Default::default(), parallel: true },
            cost: CostModel::memory_aware(),
            macro_size: None,
            multires: MultiresOptions::default(),
            twolevel: TwoLevelOptions::default(),
            cell_planes: CellPlanes::Auto,
        }
    }
}

/// A built structure of any kind.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum AnyGrid {
    Flat(FlatGrid),
    Macrocell(MacrocellGrid),
    Multires(Hierarchy),
    TwoLevel(Hierarchy),
    Proximity(ProximityGrid),
}

/// What a build did: the resolution choice, macro-size samples, times, sizes.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BuildReport {
    pub kind: GridKind,
    pub triangles: usize,
    pub resolution_choice: Option<ResolutionChoice>,
    pub macro_samples: Vec<MacroSample>,
    pub times: PhaseTimes,
    pub stats: StructureStats,
}

impl AnyGrid {
    pub fn kind(&self) -> GridKind {
        match self {
            AnyGrid::Flat(_) => GridKind::Flat,
            AnyGrid::Macrocell(_) => GridKind::Macrocell,
            AnyGrid::Multires(_) => GridKind::Multires,
            AnyGrid::TwoLevel(_) => GridKind::TwoLevel,
            AnyGrid::Proximity(_) => GridKind::Proximity,
        }
    }

    /// The flat grid a flat, macrocell or proximity grid stands on (`None` for the
    /// hierarchies): the compact arrays the CPU and GPU kernels read.
    pub fn flat(&self) -> Option<&FlatGrid> {
        match self {
            AnyGrid::Flat(g) => Some(g),
            AnyGrid::Macrocell(m) => Some(&m.fine),
            AnyGrid::Proximity(p) => Some(&p.grid),
            AnyGrid::Multires(_) | AnyGrid::TwoLevel(_) => None,
        }
    }

    /// [`AnyGrid::flat`], by value.
    pub fn into_flat(self) -> Option<FlatGrid> {
        match self {
            AnyGrid::Flat(g) => Some(g),
            AnyGrid::Macrocell(m) => Some(m.fine),
            AnyGrid::Proximity(p) => Some(p.grid),
            AnyGrid::Multires(_) | AnyGrid::TwoLevel(_) => None,
        }
    }

    /// The outermost grid's box and resolution.
    pub fn geometry(&self) -> &GridGeometry {
        match self {
            AnyGrid::Flat(g) => &g.geom,
            AnyGrid::Macrocell(g) => &g.fine.geom,
            AnyGrid::Multires(h) | AnyGrid::TwoLevel(h) => &h.geom,
            AnyGrid::Proximity(p) => &p.grid.geom,
        }
    }

    pub fn trace(&self, tris: &[[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> (Hit, RayStats) {
        match self {
            AnyGrid::Flat(g) => trace_flat(g, tris, ray, opts),
            AnyGrid::Macrocell(g) => g.trace(tris, ray, opts),
            AnyGrid::Multires(h) | AnyGrid::TwoLevel(h) => h.trace(tris, ray, opts),
            AnyGrid::Proximity(p) => p.trace(tris, ray, opts),
        }
    }

    pub fn trace_batch(
        &self,
        tris: &[[Vec3; 3]],
        rays: &[Ray],
        opts: TraceOptions,
        parallel: bool,
    ) -> (Vec<Hit>, BatchStats) {
        match self {
            // Amanatides–Woo on the flat, macrocell and proximity grids: incoherent rays on a
            // large grid interleaved, so that the loads of an occupied cell's offset, references and
            // triangles overlap across rays.
            AnyGrid::Flat(g) if opts.interleave && opts.traversal == Traversal::AmanatidesWoo => {
                trace_chunks(rays, parallel, |r, h| interleaved::trace_chunk(g, tris, r, h, opts))
            }
            AnyGrid::Macrocell(g) if opts.interleave && opts.traversal == Traversal::AmanatidesWoo => {
                trace_chunks(rays, parallel, |r, h| interleaved::trace_chunk(g, tris, r, h, opts))
            }
            AnyGrid::Proximity(p) if opts.interleave && opts.traversal == Traversal::AmanatidesWoo => {
                trace_chunks(rays, parallel, |r, h| interleaved::trace_chunk(p, tris, r, h, opts))
            }
            _ => trace_batch(rays, parallel, |r| self.trace(tris, r, opts)),
        }
    }

    /// Closest hits (or any hits, by `opts.query`) of an image's rays (`rays` row-major, `width` per row) in packets of
    /// coherent rays ([`crate::coherent`]): the flat grid, the macrocell grid (empty macrocells
    /// skipped per slice) and the proximity grid's cells walk slice by slice; the hierarchies
    /// walk their top grid's slices and their child grids' cells layer by layer inside them.
    /// Hits are those of [`AnyGrid::trace_batch`], bit for bit.
    pub fn trace_packets(
        &self,
        tris: &[[Vec3; 3]],
        rays: &[Ray],
        width: usize,
        opts: TraceOptions,
        packets: PacketOptions,
        parallel: bool,
    ) -> (Vec<Hit>, BatchStats, PacketStats) {
        let single = |r: &Ray| self.trace(tris, r, opts);
        match self {
            AnyGrid::Flat(g) => coherent::trace_image(g, tris, rays, width, packets, opts.query, parallel, single),
            AnyGrid::Proximity(p) => {
                coherent::trace_image(&p.grid, tris, rays, width, packets, opts.query, parallel, single)
            }
            AnyGrid::Macrocell(g) => coherent::trace_image(g, tris, rays, width, packets, opts.query, parallel, single),
            AnyGrid::Multires(h) | AnyGrid::TwoLevel(h) => {
                coherent::trace_image(h, tris, rays, width, packets, opts.query, parallel, single)
            }
        }
    }

    /// A 64-bit FNV-1a hash of the structure's arrays: the cell table (a flat grid's table of
    /// M + 1 offsets, [`FlatGrid::cell_table`], which its compact arrays determine, or a
    /// hierarchy's cells), then the references, then the kind's extra array
    /// (macrocell occupancy, proximity distances), each as little-endian words. Two builds
    /// (serial or parallel, CPU or GPU) are identical exactly when the digests are, barring a
    /// hash collision.
    pub fn cells_digest(&self) -> u64 {
        let table;
        let (cells, refs, extra_words, extra_bytes): (&[u32], &[u32], &[u32], &[u8]) = match self {
            AnyGrid::Flat(g) => {
                table = g.cell_table();
                (&table, &g.refs, &[], &[])
            }
            AnyGrid::Macrocell(g) => {
                table = g.fine.cell_table();
                (&table, &g.fine.refs, &g.occupancy, &[])
            }
            AnyGrid::Multires(h) | AnyGrid::TwoLevel(h) => (&h.cells, &h.refs, &[], &[]),
            AnyGrid::Proximity(p) => {
                table = p.grid.cell_table();
                (&table, &p.grid.refs, &[], &p.distance)
            }
        };
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        let mut eat = |b: u8| h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        for w in cells.iter().chain(refs).chain(extra_words) {
            w.to_le_bytes().into_iter().for_each(&mut eat);
        }
        extra_bytes.iter().for_each(|&b| eat(b));
        h
    }

    pub fn memory_bytes(&self) -> u64 {
        match self {
            AnyGrid::Flat(g) => g.memory_bytes(),
            AnyGrid::Macrocell(g) => g.memory_bytes(),
            AnyGrid::Multires(h) | AnyGrid::TwoLevel(h) => h.memory_bytes(),
            AnyGrid::Proximity(p) => p.memory_bytes(),
        }
    }

    pub fn stats(&self, triangles: usize) -> StructureStats {
        let mut s = match self {
            AnyGrid::Flat(g) => g.stats(triangles),
            AnyGrid::Macrocell(g) => {
                let mut s = g.fine.stats(triangles);
                let macro_cells = g.macro_res.x as u64 * g.macro_res.y as u64 * g.macro_res.z as u64;
                s.nodes = 2;
                s.levels = 2;
                s.depth_histogram = vec![macro_cells, s.cells];
                s.cells += macro_cells;
                s.macro_size = Some(g.a);
                s.occupied_macrocells = Some(g.occupied_count());
                s
            }
            AnyGrid::Multires(h) | AnyGrid::TwoLevel(h) => h.stats(triangles),
            AnyGrid::Proximity(p) => {
                let mut s = p.grid.stats(triangles);
                s.jump_cells = Some(p.jump_cells());
                s
            }
        };
        s.memory_bytes = self.memory_bytes();
        s.memory_bytes_per_triangle = s.memory_bytes as f64 / triangles.max(1) as f64;
        s
    }
}

/// Builds the structure `cfg` over `tris`.
pub fn build(tris: &[[Vec3; 3]], cfg: &GridConfig) -> Result<(AnyGrid, BuildReport), BuildError> {
    build_with(tris, cfg, None)
}

/// [`build`] for a grid rebuilt every frame: the flat and proximity grids' arrays come from
/// `scratch` (hand the previous frame's grid back with [`BuildScratch::recycle`]). The same
/// grid as [`build`].
pub fn build_reusing(
    tris: &[[Vec3; 3]],
    cfg: &GridConfig,
    scratch: &mut BuildScratch,
) -> Result<(AnyGrid, BuildReport), BuildError> {
    build_with(tris, cfg, Some(scratch))
}

fn build_with(
    tris: &[[Vec3; 3]],
    cfg: &GridConfig,
    scratch: Option<&mut BuildScratch>,
) -> Result<(AnyGrid, BuildReport), BuildError> {
    if cfg.build.parallel {
        return crate::build::on_pool(|| build_on(tris, cfg, scratch));
    }
    build_on(tris, cfg, scratch)
}

/// Gives `grid` its cell slabs when `cfg.cell_planes` wants them (`eligible`: its kind and
/// insertion qualify under [`CellPlanes::Auto`]), timed as the "planes" phase.
fn add_planes(grid: &mut FlatGrid, tris: &[[Vec3; 3]], cfg: &GridConfig, eligible: bool, times: &mut PhaseTimes) {
    if cell_plane::wanted(grid, cfg.cell_planes, eligible) {
        grid.planes = times.record("planes", || cell_plane::planes_of(grid, tris, cfg.cell_planes, cfg.build.parallel));
    }
}

fn build_on(
    tris: &[[Vec3; 3]],
    cfg: &GridConfig,
    scratch: Option<&mut BuildScratch>,
) -> Result<(AnyGrid, BuildReport), BuildError> {
    let mut times = PhaseTimes::default();
    let (bounds, extents) = times.record("bounds", || triangle_bounds_and_extents(tris, cfg.build.parallel));
    let choose = |times: &mut PhaseTimes, policy: Resolution| {
        times.record("resolution", || {
            resolution::choose_with(
                tris,
                &bounds,
                Some(&extents),
                policy,
                &cfg.cost,
                cfg.build.insert,
                cfg.build.parallel,
            )
        })
    };
    // Every resolution, explicit or chosen, obeys the same cell limit as the auto choice.
    let choose = |times: &mut PhaseTimes, policy: Resolution| -> Result<ResolutionChoice, BuildError> {
        let c = choose(times, policy);
        crate::build::check_cells(c.resolution, cfg.cost.max_cells)?;
        Ok(c)
    };
    let mut macro_samples = Vec::new();
    let (grid, choice) = match cfg.kind {
        GridKind::Flat | GridKind::Proximity => {
            let choice = choose(&mut times, cfg.resolution.unwrap_or(Resolution::Auto))?;
            let geom = GridGeometry::new(&bounds, choice.resolution);
            let g = match scratch {
                Some(s) => FlatGrid::build_reusing(tris, geom, cfg.build, &mut times, s)?,
                None => FlatGrid::build(tris, geom, cfg.build, &mut times)?,
            };
            let grid = if cfg.kind == GridKind::Flat {
                let mut g = g;
                add_planes(&mut g, tris, cfg, cfg.build.insert == InsertMode::Exact, &mut times);
                AnyGrid::Flat(g)
            } else {
                AnyGrid::Proximity(times.record("distance", || ProximityGrid::new(g)))
            };
            (grid, Some(choice))
        }
        GridKind::Macrocell => {
            let choice = choose(&mut times, cfg.resolution.unwrap_or(Resolution::Auto))?;
            let (mut g, samples) =
                MacrocellGrid::build(tris, &bounds, choice.resolution, cfg.macro_size, cfg.build, &mut times)?;
            add_planes(&mut g.fine, tris, cfg, true, &mut times);
            macro_samples = samples;
            (AnyGrid::Macrocell(g), Some(choice))
        }
        GridKind::Multires => {
            let choice = choose(&mut times, cfg.resolution.unwrap_or(MULTIRES_TOP_DEFAULT))?;
            // The cell limit covers the sub-grids too.
            let multires = MultiresOptions {
                cost: CostModel { max_cells: cfg.cost.max_cells, ..cfg.multires.cost },
                ..cfg.multires
            };
            let h = crate::multires::build(tris, &bounds, choice.resolution, multires, cfg.build, &mut times)?;
            (AnyGrid::Multires(h), Some(choice))
        }
        GridKind::TwoLevel => {
            let (top, choice) = match cfg.resolution {
                Some(p) => {
                    let c = choose(&mut times, p)?;
                    (Some(c.resolution), Some(c))
                }
                None => (None, None),
            };
            let h = crate::twolevel::build(tris, &bounds, top, cfg.twolevel, cfg.build, cfg.cost, &mut times)?;
            (AnyGrid::TwoLevel(h), choice)
        }
    };
    let stats = grid.stats(tris.len());
    Ok((
        grid,
        BuildReport { kind: cfg.kind, triangles: tris.len(), resolution_choice: choice, macro_samples, times, stats },
    ))
}
