//! The render pass: camera rays (`camera.wgsl`) → closest hit (the structure's trace kernel) →
//! shadow rays to a point light (`shadow.wgsl`) → traced again → shading (`shade.wgsl`) into
//! RGBA8 pixels. Views: `shaded`, `normals`, `depth`, `heatmap-cells`, `heatmap-tests`; the
//! heatmaps map 0 … `heat_max` onto a fixed colour scale (black, blue, cyan, green, yellow,
//! red, white).
//!
//! A frame is rendered in tiles of consecutive pixels: a [`FrameTarget`] holds the per-pixel
//! buffers of one tile (at most [`FrameTarget::tile_capacity`] pixels, within the device's
//! binding and dispatch limits), so any image up to [`MAX_IMAGE_SIDE`] per side renders on any
//! adapter. [`Renderer::render`] reads each tile back as it finishes. With a display texture
//! (the app), a last pass (`present.wgsl`) copies each tile's pixels into the full-size texture
//! and sums the per-ray stats on the GPU, so the app reads back 32 bytes per frame.

use gridrt_grid::{Query, RayStats, TraceOptions, Traversal};
use gridrt_scene::{Aabb, Camera, Hit};

use crate::context::{GpuContext, GpuError};
use crate::cpu::gpu_camera;
use crate::layout::{FrameTotals, GridParams, HIT_BYTES, PIXEL_BYTES, RAY_BYTES, STATS_BYTES, ShadeParams};
use crate::trace::{TraceJob, Tracer, WORKGROUP, pipeline, read_back, records, walker_for};
use crate::upload::{GpuScene, GpuStructure};
use crate::view::View;

/// What a frame is drawn from: the scene on the device, a structure over it, and the scene's
/// bounds (they place the light and the depth range).
#[derive(Clone, Copy, Debug)]
pub struct FrameSource<'a> {
    pub scene: &'a GpuScene,
    pub structure: &'a GpuStructure,
    pub bounds: &'a Aabb,
}

/// One image request.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
    pub view: View,
    pub traversal: Traversal,
    pub mailbox: bool,
    /// Count shown as the top of the heatmap scale.
    pub heat_max: f32,
    /// Primary and shadow rays in 8×8 coherent packets (the flat and macrocell grids' packet
    /// kernels; other structures trace single rays).
    pub packets: bool,
}

impl RenderOptions {
    /// A `width` × `height` shaded image from `camera`: Amanatides–Woo with the mailbox, the
    /// heatmap scale topping out at 64.
    pub fn new(camera: Camera, width: u32, height: u32) -> RenderOptions {
        RenderOptions {
            width,
            height,
            camera,
            view: View::Shaded,
            traversal: Traversal::AmanatidesWoo,
            mailbox: true,
            heat_max: 64.0,
            packets: false,
        }
    }

    /// [`RenderOptions::new`] with the camera framing `bounds` ([`Camera::fit`]).
    pub fn fit(bounds: &Aabb, width: u32, height: u32) -> RenderOptions {
        RenderOptions::new(Camera::fit(bounds, width as f32 / height as f32), width, height)
    }
}

/// A rendered image with the primary rays' hits and stats.
#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// RGBA8, row-major from the top-left.
    pub rgba: Vec<u8>,
    pub hits: Vec<Hit>,
    pub stats: Vec<RayStats>,
    /// Wall-clock time of each pass, summed over the tiles ([`Renderer::render`] waits for the
    /// device after each).
    pub times: PassTimes,
}

/// The stages of a frame [`Renderer::render`] times apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// Camera rays and their trace.
    Primary,
    /// Shadow rays from the primary hits and their trace (occlusion queries; shaded view).
    Shadow,
}

/// Milliseconds per [`Pass`] (the rest of a frame, shading and the read-back, is in neither).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    pub primary_ms: f64,
    /// `None` when the view traces no shadow rays.
    pub shadow_ms: Option<f64>,
}

/// What one tile of a frame is drawn from and into ([`Renderer::encode_tile`]'s arguments).
struct Tile<'a> {
    src: &'a FrameSource<'a>,
    o: &'a RenderOptions,
    t: &'a FrameTarget,
    pixels: std::ops::Range<u32>,
}

/// The light the shaded view uses: above and to the side of the scene.
pub fn light_position(bounds: &Aabb) -> glam::Vec3 {
    bounds.center() + glam::Vec3::new(0.35, 1.0, 0.55) * bounds.diagonal()
}

/// Largest image side the render pass accepts.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// The texture format of a display target: `rgba8unorm` holding display-encoded (gamma) values,
/// what egui expects of a texture it samples (it blends in gamma space).
pub const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Most pixels in one tile: 2^20 keeps a tile's buffers near 120 MB.
pub const MAX_TILE_PIXELS: u32 = 1 << 20;

/// Buffers for frames of one size, reused across frames: the per-pixel buffers of one tile,
/// and optionally the full-size display texture.
#[derive(Debug)]
pub struct FrameTarget {
    pub width: u32,
    pub height: u32,
    /// Pixels the per-pixel buffers hold: the largest tile.
    capacity: u32,
    camera: wgpu::Buffer,
    shade: wgpu::Buffer,
    trace_params: wgpu::Buffer,
    /// The shadow pass's: the same with `query` any.
    shadow_params: wgpu::Buffer,
    rays: wgpu::Buffer,
    pub hits: wgpu::Buffer,
    pub stats: wgpu::Buffer,
    shadow_rays: wgpu::Buffer,
    shadow_hits: wgpu::Buffer,
    shadow_stats: wgpu::Buffer,
    pub pixels: wgpu::Buffer,
    totals: wgpu::Buffer,
    /// `FrameTotals` copied here at the end of each displayed frame (MAP_READ).
    pub totals_read: wgpu::Buffer,
    /// RGBA8 image (display targets only): storage-written, sampled via [`Self::display_view`].
    pub texture: Option<wgpu::Texture>,
}

/// A whole buffer as a binding.
fn b(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    buffer.as_entire_binding()
}

impl FrameTarget {
    /// Allocates the buffers for `width`×`height` pixels; `display` adds the texture.
    pub fn new(ctx: &GpuContext, width: u32, height: u32, display: bool) -> Result<FrameTarget, GpuError> {
        let n = width as u64 * height as u64;
        if n == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
            return Err(GpuError::Unsupported(format!("image size {width}x{height} (1..={MAX_IMAGE_SIDE} per side)")));
        }
        let max_side = ctx.device.limits().max_texture_dimension_2d;
        if display && (width > max_side || height > max_side) {
            return Err(GpuError::Unsupported(format!(
                "frame size {width}x{height}: this device's textures are at most {max_side} pixels per side"
            )));
        }
        let capacity = (n.min(tile_limit(ctx) as u64)) as u32;
        let n = capacity as u64;
        let dev = &ctx.device;
        let buf = |label, size: u64, usage| {
            dev.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        use wgpu::BufferUsages as U;
        let storage = U::STORAGE;
        let texture = display.then(|| {
            dev.create_texture(&wgpu::TextureDescriptor {
                label: Some("frame image"),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: DISPLAY_FORMAT,
                usage: wgpu::TextureUsages::STORAGE_BINDING
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            })
        });
        Ok(FrameTarget {
            width,
            height,
            capacity,
            camera: buf("camera", size_of::<crate::layout::GpuCamera>() as u64, U::UNIFORM | U::COPY_DST),
            shade: buf("shade params", size_of::<ShadeParams>() as u64, U::UNIFORM | U::COPY_DST),
            trace_params: buf("trace params", size_of::<GridParams>() as u64, U::UNIFORM | U::COPY_DST),
            shadow_params: buf("shadow trace params", size_of::<GridParams>() as u64, U::UNIFORM | U::COPY_DST),
            rays: buf("primary rays (tile)", n * RAY_BYTES, storage),
            hits: buf("primary hits (tile)", n * HIT_BYTES, storage | U::COPY_SRC),
            stats: buf("primary stats (tile)", n * STATS_BYTES, storage | U::COPY_SRC),
            shadow_rays: buf("shadow rays (tile)", n * RAY_BYTES, storage),
            shadow_hits: buf("shadow hits (tile)", n * HIT_BYTES, storage),
            shadow_stats: buf("shadow stats (tile)", n * STATS_BYTES, storage),
            pixels: buf("pixels (tile)", n * PIXEL_BYTES, storage | U::COPY_SRC),
            totals: buf("frame totals", size_of::<FrameTotals>() as u64, storage | U::COPY_SRC | U::COPY_DST),
            totals_read: buf("frame totals readback", size_of::<FrameTotals>() as u64, U::MAP_READ | U::COPY_DST),
            texture,
        })
    }

    /// Pixels per frame.
    pub fn pixel_count(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// Most pixels one tile may have ([`Renderer::encode_tile`]).
    pub fn tile_capacity(&self) -> u32 {
        self.capacity
    }

    /// Puts an RGBA8 image of the target's size made elsewhere (a frame traced on the CPU) into
    /// the display texture, after the work already submitted.
    pub fn write_image(&self, ctx: &GpuContext, rgba: &[u8]) -> Result<(), GpuError> {
        let texture =
            self.texture.as_ref().ok_or(GpuError::Unsupported("an image for a target without a texture".into()))?;
        if rgba.len() != self.width as usize * self.height as usize * 4 {
            return Err(GpuError::Unsupported(format!(
                "an image of {} bytes for a {}x{} target",
                rgba.len(),
                self.width,
                self.height
            )));
        }
        ctx.queue.write_texture(
            texture.as_image_copy(),
            rgba,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(self.width * 4), rows_per_image: None },
            wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
        );
        Ok(())
    }

    /// A sampling view of the display texture (for egui); `None` without a texture.
    pub fn display_view(&self) -> Option<wgpu::TextureView> {
        self.texture.as_ref().map(|t| {
            t.create_view(&wgpu::TextureViewDescriptor {
                label: Some("frame image (sampling view)"),
                usage: Some(wgpu::TextureUsages::TEXTURE_BINDING),
                ..Default::default()
            })
        })
    }

    /// Reads `totals_read` after its `map_async` completed, and unmaps it.
    pub fn take_totals(&self) -> Result<FrameTotals, GpuError> {
        let slice = self.totals_read.slice(..);
        let view =
            slice.get_mapped_range().map_err(|e| GpuError::Readback { what: "frame totals", detail: e.to_string() })?;
        let t: FrameTotals = bytemuck::pod_read_unaligned(&view);
        drop(view);
        self.totals_read.unmap();
        Ok(t)
    }
}

/// Largest tile this device can run: every per-pixel binding (32-byte rays the largest) within
/// the storage-binding and buffer limits, one dispatch, at most [`MAX_TILE_PIXELS`]; a multiple
/// of the workgroup size.
pub fn tile_limit(ctx: &GpuContext) -> u32 {
    let l = ctx.device.limits();
    let by_binding = l.max_storage_buffer_binding_size.min(l.max_buffer_size) / 32;
    let by_dispatch = l.max_compute_workgroups_per_dimension as u64 * WORKGROUP as u64;
    let n = by_binding.min(by_dispatch).min(MAX_TILE_PIXELS as u64) as u32;
    (n / WORKGROUP * WORKGROUP).max(WORKGROUP)
}

/// The shading constants of a frame: light, view, heatmap scale, depth range.
pub fn shade_params(bounds: &Aabb, o: &RenderOptions) -> ShadeParams {
    let radius = bounds.diagonal() * 0.5;
    let eye_dist = gridrt_scene::scaled::length_scaled(o.camera.eye - bounds.center());
    ShadeParams {
        light: light_position(bounds).to_array(),
        diagonal: bounds.diagonal(),
        view: o.view.code(),
        heat_max: o.heat_max.max(1.0),
        width: o.width,
        height: o.height,
        depth_near: (eye_dist - radius).max(0.0),
        depth_far: eye_dist + radius,
        first_pixel: 0,
        pixel_count: o.width * o.height,
    }
}

/// Render pipelines (the trace kernels come from a [`Tracer`]).
#[derive(Debug)]
pub struct Renderer {
    pub tracer: Tracer,
    camera: wgpu::ComputePipeline,
    shadow: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
    present: wgpu::ComputePipeline,
}

impl Renderer {
    pub fn new(ctx: &GpuContext) -> Result<Renderer, GpuError> {
        Ok(Renderer {
            tracer: Tracer::new(),
            camera: pipeline(ctx, "camera.wgsl", "camera_rays")?,
            shadow: pipeline(ctx, "shadow.wgsl", "shadow_rays_from_hits")?,
            shade: pipeline(ctx, "shade.wgsl", "shade_pixels")?,
            present: pipeline(ctx, "present.wgsl", "present")?,
        })
    }

    /// Records the pixels `pixels` = `[first, first + count)` of a frame (row-major) into `enc`: camera rays,
    /// trace, shadow rays and trace (shaded view), shading, and for a display target the copy
    /// into the texture and the stats totals (cleared by the tile at pixel 0, copied to
    /// `totals_read` by the last tile). The tile's pixels land at the start of the target's
    /// per-pixel buffers; `count` is at most [`FrameTarget::tile_capacity`].
    ///
    /// Uniforms and per-pixel buffers are shared by all tiles, so **each tile must be submitted
    /// before the next one is encoded** (the queue runs them in order). Tiles keep each
    /// submission short: the app stays responsive on a software adapter, and a browser never
    /// sees a dispatch long enough to lose the device.
    pub fn encode_tile(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        src: &FrameSource,
        o: &RenderOptions,
        t: &FrameTarget,
        pixels: std::ops::Range<u32>,
    ) -> Result<(), GpuError> {
        self.encode_passes(ctx, enc, Tile { src, o, t, pixels }, &mut |_, _| Ok(()))
    }

    /// [`Renderer::encode_tile`] of `tile`, calling `after(enc, pass)` once each [`Pass`] is
    /// recorded (a caller may submit `enc` there and go on in a fresh encoder).
    fn encode_passes(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        Tile { src, o, t, pixels }: Tile,
        after: &mut dyn FnMut(&mut wgpu::CommandEncoder, Pass) -> Result<(), GpuError>,
    ) -> Result<(), GpuError> {
        let FrameSource { scene, structure: s, bounds } = *src;
        let (first, count) = (pixels.start, pixels.end.saturating_sub(pixels.start));
        if (o.width, o.height) != (t.width, t.height) {
            return Err(GpuError::Unsupported(format!(
                "render of {}x{} into a {}x{} target",
                o.width, o.height, t.width, t.height
            )));
        }
        let n = t.pixel_count();
        if count == 0 || count > t.capacity || first as u64 + count as u64 > n {
            return Err(GpuError::Unsupported(format!(
                "tile of {count} pixels at {first} in a frame of {n} (at most {} per tile)",
                t.capacity
            )));
        }
        let walker = walker_for(o.traversal)?;
        let dev = &ctx.device;
        let q = &ctx.queue;
        let cam = gpu_camera(&o.camera, o.width, o.height);
        q.write_buffer(&t.camera, 0, bytemuck::bytes_of(&cam));
        let sp = ShadeParams { first_pixel: first, pixel_count: count, ..shade_params(bounds, o) };
        q.write_buffer(&t.shade, 0, bytemuck::bytes_of(&sp));
        let topts = TraceOptions {
            traversal: o.traversal,
            mailbox: o.mailbox,
            query: Query::Closest,
            ..TraceOptions::default()
        };
        let (tp, image) = crate::trace::dispatch_params(s, (first, count), topts, o.packets.then_some(o.width));
        q.write_buffer(&t.trace_params, 0, bytemuck::bytes_of(&tp));
        // Shadow rays ask only whether anything occludes the light: any hit.
        let (sp, _) = crate::trace::dispatch_params(s, (first, count), topts.occlusion(), o.packets.then_some(o.width));
        q.write_buffer(&t.shadow_params, 0, bytemuck::bytes_of(&sp));

        let groups = count.div_ceil(WORKGROUP);
        let bind = |pipe: &wgpu::ComputePipeline, label, res: &[wgpu::BindingResource]| {
            let entries: Vec<wgpu::BindGroupEntry> = res
                .iter()
                .enumerate()
                .map(|(i, r)| wgpu::BindGroupEntry { binding: i as u32, resource: r.clone() })
                .collect();
            dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout: &pipe.get_bind_group_layout(0),
                entries: &entries,
            })
        };
        let run = |enc: &mut wgpu::CommandEncoder, pipe: &wgpu::ComputePipeline, bg: &wgpu::BindGroup, label| {
            let mut pass =
                enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(label), timestamp_writes: None });
            pass.set_pipeline(pipe);
            pass.set_bind_group(0, bg, &[]);
            pass.dispatch_workgroups(groups, 1, 1);
        };
        // The tile's records of each per-pixel buffer.
        let r = |buf, stride| records(buf, count, stride);
        let (rays, hits, stats) = (r(&t.rays, RAY_BYTES), r(&t.hits, HIT_BYTES), r(&t.stats, STATS_BYTES));
        let (pixels, shade) = (r(&t.pixels, PIXEL_BYTES), b(&t.shade));
        let camera_bg = bind(&self.camera, "camera bind group", &[b(&t.camera), rays.clone(), shade.clone()]);
        run(enc, &self.camera, &camera_bg, "camera rays");
        let trace = |enc: &mut wgpu::CommandEncoder, params, rays, hits, stats| {
            let job = TraceJob { scene, structure: s, params, rays, hits, stats, count, walker, image };
            self.tracer.encode(ctx, enc, &job)
        };
        trace(enc, &t.trace_params, &t.rays, &t.hits, &t.stats)?;
        after(enc, Pass::Primary)?;
        if o.view == View::Shaded {
            let shadow_bg = bind(
                &self.shadow,
                "shadow bind group",
                &[shade.clone(), rays.clone(), hits.clone(), r(&t.shadow_rays, RAY_BYTES)],
            );
            run(enc, &self.shadow, &shadow_bg, "shadow rays");
            trace(enc, &t.shadow_params, &t.shadow_rays, &t.shadow_hits, &t.shadow_stats)?;
            after(enc, Pass::Shadow)?;
        }
        let shade_bg = bind(
            &self.shade,
            "shade bind group",
            &[
                shade.clone(),
                rays,
                hits.clone(),
                stats.clone(),
                r(&t.shadow_hits, HIT_BYTES),
                b(&scene.triangles),
                pixels.clone(),
            ],
        );
        run(enc, &self.shade, &shade_bg, "shade");
        if let Some(tex) = &t.texture {
            let view = tex.create_view(&wgpu::TextureViewDescriptor {
                label: Some("frame image (storage view)"),
                ..Default::default()
            });
            if first == 0 {
                enc.clear_buffer(&t.totals, 0, None);
            }
            let present_bg = bind(
                &self.present,
                "present bind group",
                &[shade, pixels, hits, stats, b(&t.totals), wgpu::BindingResource::TextureView(&view)],
            );
            run(enc, &self.present, &present_bg, "present");
            if first as u64 + count as u64 == n {
                enc.copy_buffer_to_buffer(&t.totals, 0, &t.totals_read, 0, size_of::<FrameTotals>() as u64);
            }
        }
        Ok(())
    }

    /// Renders one frame tile by tile, reading each tile back as it finishes; each tile's
    /// passes are submitted and waited for one by one, so that the frame's [`PassTimes`] are
    /// the passes' own.
    pub fn render(&self, ctx: &GpuContext, src: &FrameSource, o: &RenderOptions) -> Result<Frame, GpuError> {
        let t = FrameTarget::new(ctx, o.width, o.height, false)?;
        let n = t.pixel_count();
        let cap = t.tile_capacity() as u64;
        let dev = &ctx.device;
        let read = |label, size| {
            dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let pixels_read = read("pixels readback", cap * PIXEL_BYTES);
        let hits_read = read("hits readback", cap * HIT_BYTES);
        let stats_read = read("stats readback", cap * STATS_BYTES);
        let mut frame = Frame {
            width: o.width,
            height: o.height,
            rgba: Vec::with_capacity(n as usize * 4),
            hits: Vec::with_capacity(n as usize),
            stats: Vec::with_capacity(n as usize),
            times: PassTimes::default(),
        };
        let mut first = 0u64;
        while first < n {
            let count = cap.min(n - first);
            let new_encoder =
                || dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("render tile") });
            let mut enc = new_encoder();
            let mut since = web_time::Instant::now();
            let times = &mut frame.times;
            let mut after = |enc: &mut wgpu::CommandEncoder, pass: Pass| {
                ctx.queue.submit([std::mem::replace(enc, new_encoder()).finish()]);
                ctx.wait_idle("a render pass")?;
                let ms = since.elapsed().as_secs_f64() * 1e3;
                match pass {
                    Pass::Primary => times.primary_ms += ms,
                    Pass::Shadow => *times.shadow_ms.get_or_insert(0.0) += ms,
                }
                since = web_time::Instant::now();
                Ok(())
            };
            let tile = Tile { src, o, t: &t, pixels: first as u32..(first + count) as u32 };
            self.encode_passes(ctx, &mut enc, tile, &mut after)?;
            enc.copy_buffer_to_buffer(&t.pixels, 0, &pixels_read, 0, count * PIXEL_BYTES);
            enc.copy_buffer_to_buffer(&t.hits, 0, &hits_read, 0, count * HIT_BYTES);
            enc.copy_buffer_to_buffer(&t.stats, 0, &stats_read, 0, count * STATS_BYTES);
            ctx.queue.submit([enc.finish()]);
            let px: Vec<u32> = read_back(ctx, &pixels_read, count * PIXEL_BYTES, "pixels")?;
            let h: Vec<Hit> = read_back(ctx, &hits_read, count * HIT_BYTES, "hits")?;
            let st: Vec<RayStats> = read_back(ctx, &stats_read, count * STATS_BYTES, "ray stats")?;
            ctx.check_device()?;
            frame.rgba.extend(px.iter().flat_map(|p| p.to_le_bytes()));
            frame.hits.extend(h);
            frame.stats.extend(st);
            first += count;
        }
        Ok(frame)
    }
}
