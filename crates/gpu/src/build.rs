//! A flat grid built on the GPU, bit-identical to the CPU's: the scene's bounds
//! (`build_bounds.wgsl`), per-cell counts (`build_count.wgsl`), their exclusive prefix sum
//! (`build_scan.wgsl` per block of 512, block sums scanned recursively, `build_scan_add.wgsl`),
//! the scatter of triangle indices (`build_scatter.wgsl`) and each cell's references sorted
//! (`build_sort_cells.wgsl`). Insertion is by bounding box with the conservative margin, the
//! same f32 rule as `gridrt_grid::insert::box_cell_range`; the resolution is chosen on the CPU
//! from the GPU's bounds (the cost model samples triangles). The result is a
//! [`GpuStructure`] the trace and render kernels use directly, and can be read back as a
//! [`FlatGrid`].

use gridrt_grid::build::{MAX_REFS, PhaseTimes};
use gridrt_grid::geometry::{GridGeometry, INSERT_MARGIN_CELLS};
use gridrt_grid::{FlatGrid, GridKind};
use gridrt_scene::Aabb;
use wgpu::util::DeviceExt;

use crate::context::{GpuContext, GpuError};
use crate::layout::{BuildParams, GridParams};
use crate::trace::{pipeline, read_back};
use crate::upload::{GpuScene, GpuStructure};

/// Invocations per workgroup of the per-triangle and per-cell passes (the WGSL's).
const GROUP: u32 = 64;
/// Elements one workgroup of the scan covers.
const SCAN_BLOCK: u32 = 512;
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
    sort: wgpu::ComputePipeline,
}

/// A flat grid on the GPU, and what its build measured.
#[derive(Debug)]
pub struct GpuFlatGrid {
    pub geom: GridGeometry,
    pub structure: GpuStructure,
    pub cells: u64,
    pub refs: u64,
    /// Milliseconds per phase (each phase waits for the GPU).
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
            sort: pipeline(ctx, "build_sort_cells.wgsl", "build_sort_cells")?,
        })
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

    fn submit_and_read(
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
        read_back(ctx, &read, words * WORD, what)
    }

    fn encoder(ctx: &GpuContext, label: &'static str) -> wgpu::CommandEncoder {
        ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }

    /// The bounds of the scene's triangles (exactly the CPU's: min and max are exact).
    pub fn bounds(&self, ctx: &GpuContext, scene: &GpuScene) -> Result<Aabb, GpuError> {
        let keys = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grid build bounds"),
            contents: bytemuck::cast_slice(&[u32::MAX, u32::MAX, u32::MAX, 0, 0, 0]),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
        let mut enc = Self::encoder(ctx, "grid build: bounds");
        let params = BuildParams { triangle_count: scene.triangle_count, ..Default::default() };
        let groups = scene.triangle_count.div_ceil(GROUP);
        Self::pass(ctx, &mut enc, &self.bounds, "build_bounds", params, groups, &[&scene.triangles, &keys])?;
        let k = Self::submit_and_read(ctx, enc, &keys, 0, 6, "the scene bounds")?;
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

    /// Builds the flat grid `geom` over the scene's triangles (box insertion).
    pub fn build_flat(&self, ctx: &GpuContext, scene: &GpuScene, geom: GridGeometry) -> Result<GpuFlatGrid, GpuError> {
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
        Self::pass(
            ctx,
            &mut enc,
            &self.count,
            "build_count",
            params,
            n.div_ceil(GROUP),
            &[&scene.triangles, &cell_start],
        )?;
        self.scan(ctx, &mut enc, &cell_start, cells + 1)?;
        let total = Self::submit_and_read(ctx, enc, &cell_start, cells * WORD, 1, "the reference count")?[0] as u64;
        times.record_since("count + scan", start);
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
            &self.scatter,
            "build_scatter",
            params,
            n.div_ceil(GROUP),
            &[&scene.triangles, &cursor, &refs],
        )?;
        ctx.queue.submit([enc.finish()]);
        wait(ctx)?;
        times.record_since("scatter", start);
        let start = web_time::Instant::now();
        let mut enc = Self::encoder(ctx, "grid build: sort cells");
        let groups = (cells as u32).div_ceil(GROUP);
        Self::pass(ctx, &mut enc, &self.sort, "build_sort_cells", params, groups, &[&cell_start, &refs])?;
        ctx.queue.submit([enc.finish()]);
        wait(ctx)?;
        times.record_since("sort cells", start);
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
            cells: cell_start,
            extra: None,
            bytes: (cells + 1 + total) * WORD,
        };
        Ok(GpuFlatGrid { geom, structure, cells, refs: total, times })
    }

    /// The grid's cell table and references, read back into the CPU's form.
    pub fn read_back(&self, ctx: &GpuContext, grid: &GpuFlatGrid) -> Result<FlatGrid, GpuError> {
        let cell_start = Self::submit_and_read(
            ctx,
            Self::encoder(ctx, "grid readback"),
            &grid.structure.cells,
            0,
            grid.cells + 1,
            "the cells",
        )?;
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
            )?
        };
        Ok(FlatGrid::new(grid.geom, cell_start, refs))
    }
}

/// Waits until the queue is idle.
fn wait(ctx: &GpuContext) -> Result<(), GpuError> {
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map(|_| ())
        .map_err(|e| GpuError::Device(format!("waiting for the grid build: {e}")))
}
