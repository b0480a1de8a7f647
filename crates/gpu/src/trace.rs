//! The trace pass: rays in → closest hits and per-ray stats out, through the kernel of the
//! structure's kind (`shaders/<kind>.wgsl`). Same binary formats as the CPU; large ray sets are
//! processed in chunks that fit the device limits.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use gridrt_grid::{RayStats, TraceOptions, Traversal};
use gridrt_scene::{Hit, Ray};
use wgpu::util::DeviceExt;

use crate::context::{GpuContext, GpuError};
use crate::kernel::{GpuWalker, Kernel};
use crate::layout::{GpuRay, GridParams, HIT_BYTES, RAY_BYTES, STATS_BYTES, query_code};
use crate::shaders::{HitFloat, compose_for};
use crate::upload::{GpuScene, GpuStructure};

/// Threads per workgroup of every kernel (`@workgroup_size(64)`).
pub const WORKGROUP: u32 = 64;

/// The GPU walker of `traversal`, or an error for naive Bresenham (incomplete by design, so it
/// has no kernel).
pub fn walker_for(traversal: Traversal) -> Result<GpuWalker, GpuError> {
    GpuWalker::for_traversal(traversal)
        .ok_or_else(|| GpuError::Unsupported("naive Bresenham has no GPU kernel (it is incomplete by design)".into()))
}

/// Creates a compute pipeline for `entry` in the composed shader `file` (auto layout).
pub(crate) fn pipeline(ctx: &GpuContext, file: &str, entry: &str) -> Result<wgpu::ComputePipeline, GpuError> {
    pipeline_walking(ctx, file, entry, GpuWalker::default())
}

/// [`pipeline`] composed with `walker`.
pub(crate) fn pipeline_walking(
    ctx: &GpuContext,
    file: &str,
    entry: &str,
    walker: GpuWalker,
) -> Result<wgpu::ComputePipeline, GpuError> {
    let src = compose_for(file, walker, HitFloat::for_features(ctx.device.features()))?;
    let desc = wgpu::ShaderModuleDescriptor { label: Some(file), source: wgpu::ShaderSource::Wgsl(src.into()) };
    // Every check but wgpu's loop bounding, which adds a counter and a test to every iteration
    // of every loop, and the walks' loops are the kernels' hot paths (measured in the README's
    // #18 section). The browser's WebGPU ignores these settings.
    let mut checks = wgpu::ShaderRuntimeChecks::checked();
    checks.force_loop_bounding = false;
    // SAFETY: without loop bounding, a loop that never ends would be undefined behaviour. Every
    // loop of these kernels ends: the walks leave the grid or pass the segment's end within a
    // bounded number of cells (their CPU twins, tested against them, take the same steps), and
    // every other loop runs over a bounded range (references, slices, levels, a prefix sum's
    // rounds).
    #[allow(unsafe_code)]
    let module = unsafe { ctx.device.create_shader_module_trusted(desc, checks) };
    Ok(ctx.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    }))
}

/// Trace pipelines, created on first use per kind, and the buffers of [`Tracer::trace`],
/// kept between calls.
#[derive(Debug, Default)]
pub struct Tracer {
    pipelines: Mutex<HashMap<(Kernel, GpuWalker, bool), wgpu::ComputePipeline>>,
    scratch: Mutex<Option<Scratch>>,
}

/// The ray, hit and stats buffers of one chunk and their readback copies, for up to
/// `capacity` rays. Reused by every [`Tracer::trace`] call that fits: creating them per call
/// cost a fresh allocation (page faults on a software adapter, a driver allocation on a real
/// one) of ~60 bytes per ray each time, a third of a primary-ray trace on lavapipe.
#[derive(Debug)]
struct Scratch {
    capacity: usize,
    rays: wgpu::Buffer,
    hits: wgpu::Buffer,
    stats: wgpu::Buffer,
    hits_read: wgpu::Buffer,
    stats_read: wgpu::Buffer,
    params: wgpu::Buffer,
}

impl Scratch {
    fn new(ctx: &GpuContext, capacity: usize) -> Scratch {
        let buf = |label, size: u64, usage| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let n = capacity as u64;
        Scratch {
            capacity,
            rays: buf("rays", n * RAY_BYTES, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST),
            hits: buf("hits", n * HIT_BYTES, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC),
            stats: buf("ray stats", n * STATS_BYTES, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC),
            hits_read: buf("hits readback", n * HIT_BYTES, wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST),
            stats_read: buf(
                "stats readback",
                n * STATS_BYTES,
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
            params: ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("trace params"),
                contents: bytemuck::bytes_of(&GridParams::default()),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            }),
        }
    }
}

/// One trace dispatch: the scene and structure it walks, the buffers it reads and writes (the
/// first `count` records of each), and the walker the kernel is composed with.
#[derive(Debug)]
pub struct TraceJob<'a> {
    pub scene: &'a GpuScene,
    pub structure: &'a GpuStructure,
    pub params: &'a wgpu::Buffer,
    pub rays: &'a wgpu::Buffer,
    pub hits: &'a wgpu::Buffer,
    pub stats: &'a wgpu::Buffer,
    pub count: u32,
    pub walker: GpuWalker,
    /// The rays are pixels `first .. first + count` of a row-major image this many pixels wide:
    /// traced in 8×8 packets where the structure has a packet kernel. `params` must hold the
    /// same `first_ray` and `image_width` ([`dispatch_params`] makes both).
    pub image: Option<ImageRays>,
}

/// Where a dispatch's rays lie in an image (see [`TraceJob::image`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageRays {
    pub width: u32,
    pub first: u32,
}

/// The parameters of a dispatch over `count` rays from ray `first` of the whole set with the
/// mailbox and query of `opts`, and where they lie in the image `image_width` pixels wide when
/// they are traced as one (in packets): the uniform and [`TraceJob::image`] agree by
/// construction.
pub fn dispatch_params(
    s: &GpuStructure,
    (first, count): (u32, u32),
    opts: TraceOptions,
    image_width: Option<u32>,
) -> (GridParams, Option<ImageRays>) {
    let image = image_width.map(|width| ImageRays { width, first });
    let params = GridParams {
        ray_count: count,
        mailbox: opts.mailbox as u32,
        query: query_code(opts.query),
        first_ray: first,
        image_width: image_width.unwrap_or(0),
        ..s.params
    };
    (params, image)
}

impl Tracer {
    pub fn new() -> Tracer {
        Tracer::default()
    }

    /// The pipeline of `kernel` composed with `walker`: its packet kernel when `packets`.
    fn pipeline(
        &self,
        ctx: &GpuContext,
        kernel: Kernel,
        walker: GpuWalker,
        packets: bool,
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        let mut map = self.pipelines.lock().expect("tracer lock");
        if let Some(p) = map.get(&(kernel, walker, packets)) {
            return Ok(p.clone());
        }
        let p = match kernel.packet_file().filter(|_| packets) {
            Some(file) => pipeline_walking(ctx, file, Kernel::PACKET_ENTRY, walker)?,
            None => pipeline_walking(ctx, kernel.file(), Kernel::ENTRY, walker)?,
        };
        map.insert((kernel, walker, packets), p.clone());
        Ok(p)
    }

    /// Records one trace dispatch into `enc`.
    pub fn encode(&self, ctx: &GpuContext, enc: &mut wgpu::CommandEncoder, b: &TraceJob) -> Result<(), GpuError> {
        let (scene, s) = (b.scene, b.structure);
        let kernel = Kernel::for_kind(s.kind);
        let image = b.image.filter(|_| kernel.packet_file().is_some());
        let pipe = self.pipeline(ctx, kernel, b.walker, image.is_some())?;
        let mut entries = vec![
            wgpu::BindGroupEntry { binding: 0, resource: b.params.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: records(b.rays, b.count, RAY_BYTES) },
            wgpu::BindGroupEntry { binding: 2, resource: records(b.hits, b.count, HIT_BYTES) },
            wgpu::BindGroupEntry { binding: 3, resource: records(b.stats, b.count, STATS_BYTES) },
            wgpu::BindGroupEntry { binding: 4, resource: scene.triangles.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 5, resource: s.refs.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 6, resource: s.cells.as_entire_binding() },
        ];
        if let Some(e) = &s.extra {
            entries.push(wgpu::BindGroupEntry { binding: 7, resource: e.as_entire_binding() });
        }
        if let Some(o) = &s.occupied {
            entries.push(wgpu::BindGroupEntry { binding: 8, resource: o.as_entire_binding() });
        }
        let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("trace bind group"),
            layout: &pipe.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut pass =
            enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("trace pass"), timestamp_writes: None });
        pass.set_pipeline(&pipe);
        pass.set_bind_group(0, &bind, &[]);
        match image {
            // One workgroup per 8×8 tile of the rows the rays span.
            Some(ImageRays { width, first }) => {
                let rows = (first + b.count.max(1) - 1) / width - first / width + 1;
                let edge = Kernel::PACKET_EDGE;
                pass.dispatch_workgroups(width.div_ceil(edge), rows.div_ceil(edge), 1);
            }
            None => pass.dispatch_workgroups(b.count.div_ceil(WORKGROUP), 1, 1),
        }
        Ok(())
    }

    /// Traces `rays` (closest or any hits, by `opts.query`) and reads back hits and stats
    /// (chunked).
    pub fn trace(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        s: &GpuStructure,
        rays: &[Ray],
        opts: TraceOptions,
    ) -> Result<(Vec<Hit>, Vec<RayStats>), GpuError> {
        self.trace_rays(ctx, scene, s, rays, None, opts)
    }

    /// [`Tracer::trace`] for the rays of a row-major image `width` pixels wide: in 8×8 packets
    /// where the structure has a packet kernel (flat, macrocell), else one ray per invocation.
    pub fn trace_image(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        s: &GpuStructure,
        rays: &[Ray],
        width: u32,
        opts: TraceOptions,
    ) -> Result<(Vec<Hit>, Vec<RayStats>), GpuError> {
        self.trace_rays(ctx, scene, s, rays, Some(width.max(1)), opts)
    }

    fn trace_rays(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        s: &GpuStructure,
        rays: &[Ray],
        width: Option<u32>,
        opts: TraceOptions,
    ) -> Result<(Vec<Hit>, Vec<RayStats>), GpuError> {
        let limits = ctx.device.limits();
        let max_by_binding = limits.max_storage_buffer_binding_size / std::mem::size_of::<GpuRay>() as u64;
        let max_by_dispatch = limits.max_compute_workgroups_per_dimension as u64 * WORKGROUP as u64;
        let mut chunk = (1u64 << 20).min(max_by_binding).min(max_by_dispatch).max(1) as usize;
        if let Some(w) = width {
            // Whole packet bands per chunk, within the dispatch limit on both axes.
            let band = w as usize * Kernel::PACKET_EDGE as usize;
            let by_rows = limits.max_compute_workgroups_per_dimension as usize * band;
            chunk = (chunk.min(by_rows) / band).max(1) * band;
        }
        let walker = walker_for(opts.traversal)?;
        let n = chunk.min(rays.len().max(1));
        let mut scratch = self.scratch.lock().expect("tracer scratch lock");
        if scratch.as_ref().is_none_or(|b| b.capacity < n) {
            *scratch = Some(Scratch::new(ctx, n));
        }
        let b = scratch.as_ref().expect("scratch buffers were just made");
        let out = self.trace_chunks(ctx, scene, s, rays, (chunk, width), (walker, opts), b);
        if out.is_err() {
            // A failed readback may leave a buffer mapped: the next call starts afresh.
            *scratch = None;
        }
        out
    }

    /// [`Tracer::trace`]'s chunk loop over `b`: `chunk` rays per dispatch.
    #[allow(clippy::too_many_arguments)]
    fn trace_chunks(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        s: &GpuStructure,
        rays: &[Ray],
        (chunk, width): (usize, Option<u32>),
        (walker, opts): (GpuWalker, TraceOptions),
        b: &Scratch,
    ) -> Result<(Vec<Hit>, Vec<RayStats>), GpuError> {
        let mut all_hits = Vec::with_capacity(rays.len());
        let mut all_stats = Vec::with_capacity(rays.len());
        for (ci, part) in rays.chunks(chunk).enumerate() {
            let count = part.len() as u32;
            let (p, image) = dispatch_params(s, ((ci * chunk) as u32, count), opts, width);
            ctx.queue.write_buffer(&b.params, 0, bytemuck::bytes_of(&p));
            ctx.queue.write_buffer(&b.rays, 0, bytemuck::cast_slice(part));
            let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("trace") });
            let (params, rays, hits, stats) = (&b.params, &b.rays, &b.hits, &b.stats);
            let job = TraceJob { scene, structure: s, params, rays, hits, stats, count, walker, image };
            self.encode(ctx, &mut enc, &job)?;
            let (hit_bytes, stat_bytes) = (count as u64 * HIT_BYTES, count as u64 * STATS_BYTES);
            enc.copy_buffer_to_buffer(&b.hits, 0, &b.hits_read, 0, hit_bytes);
            enc.copy_buffer_to_buffer(&b.stats, 0, &b.stats_read, 0, stat_bytes);
            ctx.queue.submit([enc.finish()]);
            // Both maps wait on one poll, and the bytes go straight into the results.
            let [hit_slice, stat_slice] =
                map_for_reading(ctx, [(&b.hits_read, hit_bytes), (&b.stats_read, stat_bytes)], "hits and ray stats")?;
            // A pipeline or bind group the device refused leaves the buffers as they were:
            // an error, not hits.
            ctx.check_device()?;
            {
                let err = |what, e: &dyn std::fmt::Display| GpuError::Readback { what, detail: e.to_string() };
                let view = hit_slice.get_mapped_range().map_err(|e| err("hits", &e))?;
                all_hits.extend_from_slice(bytemuck::cast_slice::<u8, Hit>(&view));
                let view = stat_slice.get_mapped_range().map_err(|e| err("ray stats", &e))?;
                all_stats.extend_from_slice(bytemuck::cast_slice::<u8, RayStats>(&view));
            }
            b.hits_read.unmap();
            b.stats_read.unmap();
        }
        Ok((all_hits, all_stats))
    }
}

/// The first `count` records of a buffer of `stride`-byte records, as a binding.
pub fn records(buffer: &wgpu::Buffer, count: u32, stride: u64) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: std::num::NonZeroU64::new(count.max(1) as u64 * stride),
    })
}

/// The granularity of tile sizes, in pixels: the storage-binding offset alignment for the
/// smallest record (4-byte pixels), at least 64. Tiles are bound from the start of the
/// per-pixel buffers, so this only keeps tiles whole multiples of the workgroup.
pub fn tile_quantum(ctx: &GpuContext) -> u32 {
    (ctx.device.limits().min_storage_buffer_offset_alignment / 4).max(64)
}

/// Maps `buffer` (MAP_READ) and copies `size` bytes out as `T`s.
pub fn read_back<T: bytemuck::Pod>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    size: u64,
    what: &'static str,
) -> Result<Vec<T>, GpuError> {
    let [slice] = map_for_reading(ctx, [(buffer, size)], what)?;
    copy_mapped(buffer, slice, what)
}

/// The `T`s of a mapped `slice` of `buffer`, which is unmapped afterwards.
fn copy_mapped<T: bytemuck::Pod>(
    buffer: &wgpu::Buffer,
    slice: wgpu::BufferSlice<'_>,
    what: &'static str,
) -> Result<Vec<T>, GpuError> {
    let view = slice.get_mapped_range().map_err(|e| GpuError::Readback { what, detail: e.to_string() })?;
    let out = bytemuck::cast_slice(&view).to_vec();
    drop(view);
    buffer.unmap();
    Ok(out)
}

/// [`read_back`] without blocking: natively the device is polled until the map completes; in a
/// browser the future resolves when the browser has mapped the buffer.
pub async fn read_back_async<T: bytemuck::Pod>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    size: u64,
    what: &'static str,
) -> Result<Vec<T>, GpuError> {
    let err = |e: &dyn std::fmt::Display| GpuError::Readback { what, detail: e.to_string() };
    let slice = buffer.slice(..size);
    let state: Arc<Mutex<MapState>> = Default::default();
    let done = state.clone();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        if let Ok(mut s) = done.lock() {
            s.result = Some(r);
            if let Some(w) = s.waker.take() {
                w.wake();
            }
        }
    });
    ctx.wait_idle(what).map_err(|e| err(&e))?;
    MapFuture(state).await.map_err(|e| err(&e))?;
    copy_mapped(buffer, slice, what)
}

/// A buffer mapping's outcome and the task waiting for it.
#[derive(Default)]
struct MapState {
    result: Option<Result<(), wgpu::BufferAsyncError>>,
    waker: Option<std::task::Waker>,
}

/// Resolves when `map_async`'s callback has run.
struct MapFuture(Arc<Mutex<MapState>>);

impl std::future::Future for MapFuture {
    type Output = Result<(), wgpu::BufferAsyncError>;
    fn poll(self: std::pin::Pin<&mut Self>, cx: &mut std::task::Context<'_>) -> std::task::Poll<Self::Output> {
        let Ok(mut s) = self.0.lock() else { return std::task::Poll::Ready(Err(wgpu::BufferAsyncError)) };
        match s.result.take() {
            Some(r) => std::task::Poll::Ready(r),
            None => {
                s.waker = Some(cx.waker().clone());
                std::task::Poll::Pending
            }
        }
    }
}

/// Maps the first `size` bytes of each MAP_READ buffer for reading, waiting once for all of
/// them, and returns the mapped slices.
fn map_for_reading<'a, const N: usize>(
    ctx: &GpuContext,
    buffers: [(&'a wgpu::Buffer, u64); N],
    what: &'static str,
) -> Result<[wgpu::BufferSlice<'a>; N], GpuError> {
    let err = |e: &dyn std::fmt::Display| GpuError::Readback { what, detail: e.to_string() };
    let slices = buffers.map(|(buffer, size)| buffer.slice(..size));
    let (tx, rx) = std::sync::mpsc::channel();
    for slice in &slices {
        let tx = tx.clone();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
    }
    ctx.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| err(&e))?;
    for _ in 0..N {
        rx.recv().map_err(|e| err(&e))?.map_err(|e| err(&e))?;
    }
    Ok(slices)
}
