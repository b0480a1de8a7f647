//! A flat grid built on the GPU, bit-identical to the CPU's: the scene's bounds
//! (`build_bounds.wgsl`), per-cell counts (`build_count.wgsl`), their exclusive prefix sum
//! (`build_scan.wgsl` per block of 4096, block sums scanned recursively, `build_scan_add.wgsl`),
//! the scatter of triangle indices (`build_scatter.wgsl`) and each cell's references sorted
//! (`build_sort_cells.wgsl`); the compact layout the trace kernels read, as
//! `FlatGrid::new` makes it (`build_cell_bits.wgsl`: an occupancy word per 32 cells and its count,
//! scanned into ranks; `build_compact.wgsl`: the occupied cells' offsets); for macrocells, the
//! occupancy bits from the occupancy words (`build_occupancy.wgsl`, per candidate A when the
//! cost model chooses A, as on the CPU).
//! Insertion is by bounding box with the conservative margin, the same f32 rule as
//! `gridrt_grid::insert::box_cell_range`, or exact (`build_insert_exact.wgsl`, counting and
//! then scattering: the CPU's separating-axis test in binary64 on u32 words,
//! `shared/overlap.wgsl`, so the same cells where WGSL has no f64); the resolution is chosen on
//! the CPU from the GPU's bounds (the cost model samples triangles). The result is a [`GpuStructure`] the trace and
//! render kernels use directly, and can be read back as the CPU's [`AnyGrid`].

use glam::{UVec3, Vec3};
use gridrt_grid::build::{MAX_REFS, PhaseTimes, check_cells};
use gridrt_grid::flat::WORD_CELLS;
use gridrt_grid::geometry::{GridGeometry, INSERT_MARGIN_CELLS};
use gridrt_grid::macrocell::{
    MACRO_SIZES, MacroSample, MacrocellGrid, best_macro_sample, check_macro_size, macro_resolution,
};
use gridrt_grid::{
    AnyGrid, FlatGrid, GridConfig, GridKind, InsertMode, OccupancyWord, Resolution, ResolutionChoice, resolution,
};
use gridrt_scene::Aabb;
use wgpu::util::DeviceExt;

use crate::context::{GpuContext, GpuError};
use crate::layout::{BuildParams, GridParams};
use crate::trace::{pipeline, read_back_async};
use crate::upload::{GpuScene, GpuStructure};

/// Invocations per workgroup of the per-triangle and per-cell passes (the WGSL's).
const GROUP: u32 = 64;
/// Workgroups of the bounds pass (each invocation folds every (groups × 64)-th triangle).
const BOUNDS_GROUPS: u32 = 256;
/// Elements one workgroup of the scan covers (build_scan.wgsl's SCAN_BLOCK).
const SCAN_BLOCK: u32 = 4096;
/// Cells each invocation of the sort pass covers (build_sort_cells.wgsl's SORT_RUN).
const SORT_RUN: u32 = 16;
/// Bytes of a u32.
const WORD: u64 = 4;

/// The build's pipelines, created once.
#[derive(Debug)]
pub struct GridBuilder {
    bounds: wgpu::ComputePipeline,
    count: wgpu::ComputePipeline,
    scan: wgpu::ComputePipeline,
    scan_add: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    /// Created at the first exact build: its shader is long (emulated f64), and a software
    /// adapter or a browser would compile it at start-up for nothing.
    insert_exact: std::sync::OnceLock<wgpu::ComputePipeline>,
    sort: wgpu::ComputePipeline,
    cell_bits: wgpu::ComputePipeline,
    compact: wgpu::ComputePipeline,
    occupancy: wgpu::ComputePipeline,
}

/// A grid built on the GPU (flat, or macrocells over a flat fine grid), and what its build
/// measured.
#[derive(Debug)]
pub struct GpuGrid {
    /// The (fine) grid's box and resolution.
    pub geom: GridGeometry,
    pub structure: GpuStructure,
    pub cells: u64,
    /// Cells holding references (entries of `ref_start` but the last).
    pub occupied_cells: u64,
    pub refs: u64,
    /// Macrocell edge A and the macro resolution.
    pub macrocells: Option<(u32, UVec3)>,
    /// The occupancy of each candidate A, when the cost model chose A.
    pub macro_samples: Vec<MacroSample>,
    /// The resolution choice (when built through [`GridBuilder::build`]).
    pub choice: Option<ResolutionChoice>,
    /// Milliseconds per phase (each GPU phase waits for the GPU).
    pub times: PhaseTimes,
}

/// A 2-D dispatch of `groups` workgroups: (x, y), x at most the device's limit.
fn dispatch_size(ctx: &GpuContext, groups: u32) -> Result<(u32, u32), GpuError> {
    let max = ctx.device.limits().max_compute_workgroups_per_dimension.max(1);
    let x = groups.clamp(1, max);
    let y = groups.div_ceil(x).max(1);
    if y > max {
        return Err(GpuError::Unsupported(format!("{groups} workgroups exceed this device's dispatch limit")));
    }
    Ok((x, y))
}

impl GridBuilder {
    pub fn new(ctx: &GpuContext) -> Result<GridBuilder, GpuError> {
        Ok(GridBuilder {
            bounds: pipeline(ctx, "build_bounds.wgsl", "build_bounds")?,
            count: pipeline(ctx, "build_count.wgsl", "build_count")?,
            scan: pipeline(ctx, "build_scan.wgsl", "build_scan")?,
            scan_add: pipeline(ctx, "build_scan_add.wgsl", "build_scan_add")?,
            scatter: pipeline(ctx, "build_scatter.wgsl", "build_scatter")?,
            insert_exact: std::sync::OnceLock::new(),
            sort: pipeline(ctx, "build_sort_cells.wgsl", "build_sort_cells")?,
            occupancy: pipeline(ctx, "build_occupancy.wgsl", "build_occupancy")?,
            cell_bits: pipeline(ctx, "build_cell_bits.wgsl", "build_cell_bits")?,
            compact: pipeline(ctx, "build_compact.wgsl", "build_compact")?,
        })
    }

    /// The exact insertion kernel, created on first use.
    fn insert_exact(&self, ctx: &GpuContext) -> Result<&wgpu::ComputePipeline, GpuError> {
        if let Some(p) = self.insert_exact.get() {
            return Ok(p);
        }
        let p = pipeline(ctx, "build_insert_exact.wgsl", "build_insert_exact")?;
        Ok(self.insert_exact.get_or_init(|| p))
    }

    /// Whether the GPU builds `cfg`: flat and macrocell grids, with either insertion.
    pub fn supports(cfg: &GridConfig) -> bool {
        matches!(cfg.kind, GridKind::Flat | GridKind::Macrocell)
    }

    /// Builds `cfg` over the scene (whose CPU copy is `tris`, for the resolution choice): flat or
    /// macrocell grids, with box or exact insertion; other kinds are refused.
    pub async fn build_async(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        tris: &[[Vec3; 3]],
        cfg: &GridConfig,
    ) -> Result<GpuGrid, GpuError> {
        if !GridBuilder::supports(cfg) {
            return Err(GpuError::Unsupported(format!(
                "the GPU build makes flat and macrocell grids (asked: {}); use the CPU build",
                cfg.kind
            )));
        }
        let mut times = PhaseTimes::default();
        let start = web_time::Instant::now();
        let bounds = self.bounds_async(ctx, scene).await?;
        times.record_since("bounds", start);
        let policy = cfg.resolution.unwrap_or(Resolution::Auto);
        let choice = times.record("resolution", || {
            resolution::choose(tris, &bounds, policy, &cfg.cost, cfg.build.insert, cfg.build.parallel)
        });
        check_cells(choice.resolution, cfg.cost.max_cells)?;
        let mut g = match cfg.kind {
            GridKind::Macrocell => {
                self.macrocell_async(ctx, scene, &bounds, choice.resolution, cfg.macro_size, cfg.build.insert).await?
            }
            _ => self.flat_async(ctx, scene, GridGeometry::new(&bounds, choice.resolution), cfg.build.insert).await?,
        };
        times.0.append(&mut g.times.0);
        g.times = times;
        g.choice = Some(choice);
        Ok(g)
    }

    /// The occupancy bits of macrocells of edge `a` over `fine` (the last on an axis cut short
    /// where the resolution is not a multiple of `a`), recorded into `enc`.
    fn occupancy(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        fine: &GpuGrid,
        a: u32,
    ) -> Result<(UVec3, wgpu::Buffer), GpuError> {
        let macro_res = macro_resolution(fine.geom.res, a);
        let words = (macro_res.x as u64 * macro_res.y as u64 * macro_res.z as u64).div_ceil(32);
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let bits = Self::buffer(ctx, "structure extra (occupancy/nodes/distance)", words, storage)?;
        let params = BuildParams {
            res: fine.geom.res.to_array(),
            count: fine.cells as u32,
            macro_edge: a,
            ..Default::default()
        };
        let groups = (fine.cells as u32).div_ceil(GROUP);
        let occupied = fine.structure.occupied.as_ref().expect("a flat grid's occupancy words");
        Self::pass(ctx, enc, &self.occupancy, "build_occupancy", params, groups, &[occupied, &bits])?;
        Ok((macro_res, bits))
    }

    /// Macrocells over a fine grid at `res`: A as given, or chosen by the cost model from the
    /// fine grid itself (as `MacrocellGrid::build` does on the CPU): one build whatever A.
    pub async fn macrocell_async(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        bounds: &Aabb,
        res: [u32; 3],
        a: Option<u32>,
        insert: InsertMode,
    ) -> Result<GpuGrid, GpuError> {
        if let Some(a) = a {
            check_macro_size(a)?;
        }
        let mut fine = self.flat_async(ctx, scene, GridGeometry::new(bounds, res), insert).await?;
        let (a, samples, (macro_res, bits)) = match a {
            Some(a) => {
                let start = web_time::Instant::now();
                let mut enc = Self::encoder(ctx, "grid build: occupancy");
                let occupancy = self.occupancy(ctx, &mut enc, &fine, a)?;
                ctx.queue.submit([enc.finish()]);
                ctx.wait_idle("the grid build")?;
                fine.times.record_since("occupancy", start);
                (a, Vec::new(), occupancy)
            }
            None => {
                // Every candidate's bits, read back for its sample; the chosen one's are kept.
                let start = web_time::Instant::now();
                let mut samples = Vec::new();
                let mut candidates = Vec::new();
                for a in MACRO_SIZES {
                    let mut enc = Self::encoder(ctx, "grid build: macrocell sample");
                    let (macro_res, bits) = self.occupancy(ctx, &mut enc, &fine, a)?;
                    let words = bits.size() / WORD;
                    let occ = Self::submit_and_read(ctx, enc, &bits, 0, words, "the macrocell occupancy").await?;
                    samples.push(MacroSample::from_occupancy(a, macro_res, &occ));
                    candidates.push((macro_res, bits));
                }
                fine.times.record_since("macro-size", start);
                let chosen = best_macro_sample(&samples);
                (samples[chosen].a, samples, candidates.swap_remove(chosen))
            }
        };
        fine.structure.kind = GridKind::Macrocell;
        fine.structure.params.macro_edge = a;
        fine.structure.bytes += bits.size();
        fine.structure.extra = Some(bits);
        fine.macrocells = Some((a, macro_res));
        fine.macro_samples = samples;
        Ok(fine)
    }

    /// Records one pass over `groups` workgroups with `params` (its `groups_x` filled in).
    fn pass(
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        pipe: &wgpu::ComputePipeline,
        label: &'static str,
        mut params: BuildParams,
        groups: u32,
        buffers: &[&wgpu::Buffer],
    ) -> Result<(), GpuError> {
        let (x, y) = dispatch_size(ctx, groups)?;
        params.groups_x = x;
        let uniform = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grid build params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let mut entries = vec![wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() }];
        for (i, b) in buffers.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry { binding: i as u32 + 1, resource: b.as_entire_binding() });
        }
        let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &pipe.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut p = enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(label), timestamp_writes: None });
        p.set_pipeline(pipe);
        p.set_bind_group(0, &bind, &[]);
        p.dispatch_workgroups(x, y, 1);
        Ok(())
    }

    fn buffer(
        ctx: &GpuContext,
        label: &'static str,
        words: u64,
        usage: wgpu::BufferUsages,
    ) -> Result<wgpu::Buffer, GpuError> {
        let size = words.max(1) * WORD;
        ctx.check_buffer(label, size, usage.contains(wgpu::BufferUsages::STORAGE))?;
        Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        }))
    }

    async fn submit_and_read(
        ctx: &GpuContext,
        mut enc: wgpu::CommandEncoder,
        src: &wgpu::Buffer,
        offset: u64,
        words: u64,
        what: &'static str,
    ) -> Result<Vec<u32>, GpuError> {
        let read = Self::buffer(
            ctx,
            "grid build readback",
            words,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        )?;
        enc.copy_buffer_to_buffer(src, offset, &read, 0, words * WORD);
        ctx.queue.submit([enc.finish()]);
        read_back_async(ctx, &read, words * WORD, what).await
    }

    fn encoder(ctx: &GpuContext, label: &'static str) -> wgpu::CommandEncoder {
        ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }

    /// The bounds of the scene's triangles (exactly the CPU's: min and max are exact).
    pub async fn bounds_async(&self, ctx: &GpuContext, scene: &GpuScene) -> Result<Aabb, GpuError> {
        let keys = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grid build bounds"),
            contents: bytemuck::cast_slice(&[u32::MAX, u32::MAX, u32::MAX, 0, 0, 0]),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
        let mut enc = Self::encoder(ctx, "grid build: bounds");
        let params = BuildParams { triangle_count: scene.triangle_count, ..Default::default() };
        let groups = scene.triangle_count.div_ceil(GROUP).clamp(1, BOUNDS_GROUPS);
        Self::pass(ctx, &mut enc, &self.bounds, "build_bounds", params, groups, &[&scene.triangles, &keys])?;
        let k = Self::submit_and_read(ctx, enc, &keys, 0, 6, "the scene bounds").await?;
        let f = |key: u32| f32::from_bits(if key & 0x8000_0000 != 0 { key & 0x7FFF_FFFF } else { !key });
        Ok(Aabb { min: glam::Vec3::new(f(k[0]), f(k[1]), f(k[2])), max: glam::Vec3::new(f(k[3]), f(k[4]), f(k[5])) })
    }

    /// Exclusive prefix sum of the first `n` words of `data`, in place (recursing on the
    /// block sums).
    fn scan(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        data: &wgpu::Buffer,
        n: u64,
    ) -> Result<(), GpuError> {
        let count = u32::try_from(n).map_err(|_| GpuError::Unsupported(format!("a scan of {n} elements")))?;
        let blocks = count.div_ceil(SCAN_BLOCK);
        let sums = Self::buffer(ctx, "grid build block sums", blocks as u64, wgpu::BufferUsages::STORAGE)?;
        let params = BuildParams { count, ..Default::default() };
        Self::pass(ctx, enc, &self.scan, "build_scan", params, blocks, &[data, &sums])?;
        if blocks > 1 {
            self.scan(ctx, enc, &sums, blocks as u64)?;
            Self::pass(ctx, enc, &self.scan_add, "build_scan_add", params, blocks, &[data, &sums])?;
        }
        Ok(())
    }

    /// Builds the flat grid `geom` over the scene's triangles with insertion `insert`.
    pub async fn flat_async(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        geom: GridGeometry,
        insert: InsertMode,
    ) -> Result<GpuGrid, GpuError> {
        // Exact insertion counts and scatters with one kernel (`BuildParams::scatter` 0, then 1).
        let (count, scatter) = match insert {
            InsertMode::BoundingBox => ((&self.count, "build_count"), (&self.scatter, "build_scatter")),
            InsertMode::Exact => {
                let exact = self.insert_exact(ctx)?;
                ((exact, "build_insert_exact"), (exact, "build_insert_exact"))
            }
        };
        let mut times = PhaseTimes::default();
        let cells = geom.cell_count();
        let n = scene.triangle_count;
        let params = BuildParams {
            grid_min: geom.min.extend(0.0).to_array(),
            inv_cell: geom.inv_cell.extend(0.0).to_array(),
            res: geom.res.to_array(),
            triangle_count: n,
            margin: INSERT_MARGIN_CELLS as f32,
            count: u32::try_from(cells).map_err(|_| GpuError::Unsupported(format!("{cells} cells")))?,
            ..Default::default()
        };
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        // Counts, then (scanned in place) cell_start: M + 1 words, the last one the total.
        let start = web_time::Instant::now();
        let cell_start = Self::buffer(ctx, "cells", cells + 1, storage)?;
        let mut enc = Self::encoder(ctx, "grid build: count and scan");
        // The exact kernel's refs binding, unused when it counts.
        let no_refs = (insert == InsertMode::Exact)
            .then(|| Self::buffer(ctx, "grid build: no refs", 1, wgpu::BufferUsages::STORAGE))
            .transpose()?;
        let count_buffers: Vec<&wgpu::Buffer> = [&scene.triangles, &cell_start].into_iter().chain(&no_refs).collect();
        Self::pass(ctx, &mut enc, count.0, count.1, params, n.div_ceil(GROUP), &count_buffers)?;
        self.scan(ctx, &mut enc, &cell_start, cells + 1)?;
        // The compact layout's occupancy words and their counts, scanned into ranks (as
        // FlatGrid::new makes them), from the scanned table; read back with the reference count.
        let words = cells.div_ceil(WORD_CELLS as u64);
        let occupied = Self::buffer(ctx, "cell occupancy words", 2 * words, storage)?;
        let ranks = Self::buffer(ctx, "grid build word ranks", words + 1, storage)?;
        let word_groups = (words as u32).div_ceil(GROUP);
        Self::pass(
            ctx,
            &mut enc,
            &self.cell_bits,
            "build_cell_bits",
            params,
            word_groups,
            &[&cell_start, &occupied, &ranks],
        )?;
        self.scan(ctx, &mut enc, &ranks, words + 1)?;
        let totals = Self::buffer(ctx, "grid build totals", 2, storage)?;
        enc.copy_buffer_to_buffer(&cell_start, cells * WORD, &totals, 0, WORD);
        enc.copy_buffer_to_buffer(&ranks, words * WORD, &totals, WORD, WORD);
        let counts = Self::submit_and_read(ctx, enc, &totals, 0, 2, "the reference and occupied cell counts").await?;
        let (total, occupied_cells) = (counts[0] as u64, counts[1] as u64);
        times.record_since("count + scan + cell bits", start);
        if total > MAX_REFS {
            return Err(GpuError::Unsupported(format!("{total} references, more than the limit of {MAX_REFS}")));
        }
        let start = web_time::Instant::now();
        let refs = Self::buffer(ctx, "refs", total, storage)?;
        let cursor = Self::buffer(
            ctx,
            "grid build cursor",
            cells + 1,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let mut enc = Self::encoder(ctx, "grid build: scatter");
        enc.copy_buffer_to_buffer(&cell_start, 0, &cursor, 0, (cells + 1) * WORD);
        Self::pass(
            ctx,
            &mut enc,
            scatter.0,
            scatter.1,
            BuildParams { scatter: 1, ..params },
            n.div_ceil(GROUP),
            &[&scene.triangles, &cursor, &refs],
        )?;
        ctx.queue.submit([enc.finish()]);
        ctx.wait_idle("the grid build")?;
        times.record_since("scatter", start);
        let start = web_time::Instant::now();
        // Each cell's references sorted, and the occupied cells' starts (the table of M + 1
        // offsets is then dropped), in one submission.
        let ref_start = Self::buffer(ctx, "ref_start", occupied_cells + 1, storage)?;
        let mut enc = Self::encoder(ctx, "grid build: sort cells, compact");
        let groups = (cells as u32).div_ceil(GROUP * SORT_RUN);
        Self::pass(ctx, &mut enc, &self.sort, "build_sort_cells", params, groups, &[&cell_start, &refs])?;
        Self::pass(
            ctx,
            &mut enc,
            &self.compact,
            "build_compact",
            params,
            word_groups,
            &[&cell_start, &occupied, &ranks, &ref_start],
        )?;
        ctx.queue.submit([enc.finish()]);
        ctx.wait_idle("the grid build")?;
        times.record_since("sort cells + compact", start);
        ctx.check_device()?;
        let structure = GpuStructure {
            kind: GridKind::Flat,
            params: GridParams {
                grid_min: params.grid_min,
                inv_cell: params.inv_cell,
                res: params.res,
                ..GridParams::default()
            },
            refs,
            cells: ref_start,
            extra: None,
            bytes: (occupied_cells + 1 + total) * WORD + occupied.size(),
            occupied: Some(occupied),
        };
        Ok(GpuGrid {
            geom,
            structure,
            cells,
            occupied_cells,
            refs: total,
            macrocells: None,
            macro_samples: Vec::new(),
            choice: None,
            times,
        })
    }

    /// The grid read back into the CPU's form.
    pub async fn read_back_async(&self, ctx: &GpuContext, grid: &GpuGrid) -> Result<AnyGrid, GpuError> {
        let ref_start = Self::submit_and_read(
            ctx,
            Self::encoder(ctx, "grid readback"),
            &grid.structure.cells,
            0,
            grid.occupied_cells + 1,
            "the occupied cells' starts",
        )
        .await?;
        let words = grid.cells.div_ceil(WORD_CELLS as u64);
        let occupied = grid.structure.occupied.as_ref().expect("a flat grid's occupancy words");
        let occupied: Vec<OccupancyWord> =
            Self::submit_and_read(ctx, Self::encoder(ctx, "grid readback"), occupied, 0, 2 * words, "the occupancy")
                .await?
                .chunks_exact(2)
                .map(|w| OccupancyWord { bits: w[0], rank: w[1] })
                .collect();
        let refs = if grid.refs == 0 {
            Vec::new()
        } else {
            Self::submit_and_read(
                ctx,
                Self::encoder(ctx, "grid readback"),
                &grid.structure.refs,
                0,
                grid.refs,
                "the refs",
            )
            .await?
        };
        let fine = FlatGrid { geom: grid.geom, occupied, ref_start, refs, planes: Vec::new() };
        Ok(match (grid.macrocells, &grid.structure.extra) {
            (Some((a, macro_res)), Some(bits)) => {
                let words = bits.size() / WORD;
                let occupancy =
                    Self::submit_and_read(ctx, Self::encoder(ctx, "grid readback"), bits, 0, words, "the occupancy")
                        .await?;
                AnyGrid::Macrocell(MacrocellGrid { fine, a, macro_res, occupancy })
            }
            _ => AnyGrid::Flat(fine),
        })
    }
}

/// Blocking forms of the build (native only; a browser cannot wait for the GPU).
#[cfg(not(target_arch = "wasm32"))]
impl GridBuilder {
    /// [`GridBuilder::build_async`], blocking.
    pub fn build(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        tris: &[[Vec3; 3]],
        cfg: &GridConfig,
    ) -> Result<GpuGrid, GpuError> {
        pollster::block_on(self.build_async(ctx, scene, tris, cfg))
    }

    /// [`GridBuilder::bounds_async`], blocking.
    pub fn bounds(&self, ctx: &GpuContext, scene: &GpuScene) -> Result<Aabb, GpuError> {
        pollster::block_on(self.bounds_async(ctx, scene))
    }

    /// [`GridBuilder::flat_async`], blocking.
    pub fn build_flat(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        geom: GridGeometry,
        insert: InsertMode,
    ) -> Result<GpuGrid, GpuError> {
        pollster::block_on(self.flat_async(ctx, scene, geom, insert))
    }

    /// [`GridBuilder::read_back_async`], blocking.
    pub fn read_back(&self, ctx: &GpuContext, grid: &GpuGrid) -> Result<AnyGrid, GpuError> {
        pollster::block_on(self.read_back_async(ctx, grid))
    }
}
