//! The render pass: camera rays (`camera.wgsl`) → closest hit (the structure's trace kernel) →
//! shadow rays to a point light (`shadow.wgsl`) → traced again → shading (`shade.wgsl`) into
//! RGBA8 pixels. Views: `shaded`, `normals`, `depth`, `heatmap-cells`, `heatmap-tests`; the
//! heatmaps map 0 … `heat_max` onto a fixed colour scale (black, blue, cyan, green, yellow,
//! red, white).

use gridrt_grid::Traversal;
use gridrt_scene::{Aabb, Camera, Hit};
use wgpu::util::DeviceExt;

use crate::context::{GpuContext, GpuError};
use crate::cpu::gpu_camera;
use crate::layout::{GpuHit, GpuRayStats, GridParams, ShadeParams};
use crate::trace::{TraceBuffers, Tracer, WORKGROUP, pipeline, read_back, traversal_code};
use crate::upload::{GpuScene, GpuStructure};

/// What the image shows (`--view`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum View {
    #[default]
    Shaded,
    Normals,
    Depth,
    HeatmapCells,
    HeatmapTests,
}

impl View {
    pub const ALL: [View; 5] = [View::Shaded, View::Normals, View::Depth, View::HeatmapCells, View::HeatmapTests];

    pub fn name(self) -> &'static str {
        match self {
            View::Shaded => "shaded",
            View::Normals => "normals",
            View::Depth => "depth",
            View::HeatmapCells => "heatmap-cells",
            View::HeatmapTests => "heatmap-tests",
        }
    }

    fn code(self) -> u32 {
        self as u32
    }
}

impl std::str::FromStr for View {
    type Err = String;
    fn from_str(s: &str) -> Result<View, String> {
        View::ALL.into_iter().find(|v| v.name() == s).ok_or_else(|| {
            format!("unknown view \"{s}\": expected shaded, normals, depth, heatmap-cells or heatmap-tests")
        })
    }
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
}

/// A rendered image with the primary rays' hits and stats.
#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// RGBA8, row-major from the top-left.
    pub rgba: Vec<u8>,
    pub hits: Vec<Hit>,
    pub stats: Vec<GpuRayStats>,
}

/// The light the shaded view uses: above and to the side of the scene.
pub fn light_position(bounds: &Aabb) -> glam::Vec3 {
    bounds.center() + glam::Vec3::new(0.35, 1.0, 0.55) * bounds.diagonal()
}

/// Render pipelines (the trace kernels come from a [`Tracer`]).
#[derive(Debug)]
pub struct Renderer {
    pub tracer: Tracer,
    camera: wgpu::ComputePipeline,
    shadow: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
}

impl Renderer {
    pub fn new(ctx: &GpuContext) -> Result<Renderer, GpuError> {
        Ok(Renderer {
            tracer: Tracer::new(),
            camera: pipeline(ctx, "camera.wgsl", "camera_rays")?,
            shadow: pipeline(ctx, "shadow.wgsl", "shadow_rays_from_hits")?,
            shade: pipeline(ctx, "shade.wgsl", "shade_pixels")?,
        })
    }

    /// Renders one frame and reads it back.
    pub fn render(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        s: &GpuStructure,
        bounds: &Aabb,
        o: &RenderOptions,
    ) -> Result<Frame, GpuError> {
        let n = o.width as u64 * o.height as u64;
        if n == 0 || o.width > 16384 || o.height > 16384 {
            return Err(GpuError::Unsupported(format!("image size {}x{} (1..=16384 per side)", o.width, o.height)));
        }
        ctx.check_buffer("camera rays", n * 32, true)?;
        if n > ctx.device.limits().max_compute_workgroups_per_dimension as u64 * WORKGROUP as u64 {
            return Err(GpuError::Unsupported(format!("{n} pixels exceed one dispatch")));
        }
        let code = traversal_code(o.traversal)?;
        let dev = &ctx.device;
        let storage = |label, size: u64, extra| {
            dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | extra,
                mapped_at_creation: false,
            })
        };
        let none = wgpu::BufferUsages::empty();
        let src = wgpu::BufferUsages::COPY_SRC;
        let rays = storage("primary rays", n * 32, none);
        let hits = storage("primary hits", n * 16, src);
        let stats = storage("primary stats", n * 8, src);
        let shadow_rays = storage("shadow rays", n * 32, none);
        let shadow_hits = storage("shadow hits", n * 16, none);
        let shadow_stats = storage("shadow stats", n * 8, none);
        let pixels = storage("pixels", n * 4, src);
        let uniform = |label, bytes: &[u8]| {
            dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::UNIFORM,
            })
        };
        let cam = gpu_camera(&o.camera, o.width, o.height);
        let cam_buf = uniform("camera", bytemuck::bytes_of(&cam));
        let radius = bounds.diagonal() * 0.5;
        let eye_dist = (o.camera.eye - bounds.center()).length();
        let shade_params = ShadeParams {
            light: light_position(bounds).extend(bounds.diagonal()).to_array(),
            view: [o.view.code(), o.heat_max.max(1.0).to_bits(), o.width, o.height],
            depth: [(eye_dist - radius).max(0.0), eye_dist + radius, 0.0, 0.0],
        };
        let shade_buf = uniform("shade params", bytemuck::bytes_of(&shade_params));
        let mut tp: GridParams = s.params;
        tp.res[3] = n as u32;
        tp.options = [code, o.mailbox as u32, s.params.options[2], 0];
        let trace_params = uniform("trace params", bytemuck::bytes_of(&tp));

        let groups = (n as u32).div_ceil(WORKGROUP);
        let bind = |pipe: &wgpu::ComputePipeline, label, bufs: &[&wgpu::Buffer]| {
            let entries: Vec<wgpu::BindGroupEntry> = bufs
                .iter()
                .enumerate()
                .map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32, resource: b.as_entire_binding() })
                .collect();
            dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout: &pipe.get_bind_group_layout(0),
                entries: &entries,
            })
        };
        let camera_bg = bind(&self.camera, "camera bind group", &[&cam_buf, &rays]);
        let shadow_bg = bind(&self.shadow, "shadow bind group", &[&shade_buf, &rays, &hits, &shadow_rays]);
        let shade_bg = bind(
            &self.shade,
            "shade bind group",
            &[&shade_buf, &rays, &hits, &stats, &shadow_hits, &scene.triangles, &pixels],
        );
        let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("render") });
        let run = |enc: &mut wgpu::CommandEncoder, pipe: &wgpu::ComputePipeline, bg: &wgpu::BindGroup, label| {
            let mut pass =
                enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(label), timestamp_writes: None });
            pass.set_pipeline(pipe);
            pass.set_bind_group(0, bg, &[]);
            pass.dispatch_workgroups(groups, 1, 1);
        };
        run(&mut enc, &self.camera, &camera_bg, "camera rays");
        let primary = TraceBuffers {
            params: &trace_params,
            rays: &rays,
            hits: &hits,
            stats: &stats,
            count: n as u32,
            traversal: code,
        };
        self.tracer.encode(ctx, &mut enc, scene, s, &primary)?;
        if o.view == View::Shaded {
            run(&mut enc, &self.shadow, &shadow_bg, "shadow rays");
            let shadow = TraceBuffers {
                params: &trace_params,
                rays: &shadow_rays,
                hits: &shadow_hits,
                stats: &shadow_stats,
                count: n as u32,
                traversal: code,
            };
            self.tracer.encode(ctx, &mut enc, scene, s, &shadow)?;
        }
        run(&mut enc, &self.shade, &shade_bg, "shade");
        let read = |label, size| {
            dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let pixels_read = read("pixels readback", n * 4);
        let hits_read = read("hits readback", n * 16);
        let stats_read = read("stats readback", n * 8);
        enc.copy_buffer_to_buffer(&pixels, 0, &pixels_read, 0, n * 4);
        enc.copy_buffer_to_buffer(&hits, 0, &hits_read, 0, n * 16);
        enc.copy_buffer_to_buffer(&stats, 0, &stats_read, 0, n * 8);
        ctx.queue.submit([enc.finish()]);
        let px: Vec<u32> = read_back(ctx, &pixels_read, n * 4, "pixels")?;
        let h: Vec<GpuHit> = read_back(ctx, &hits_read, n * 16, "hits")?;
        let st: Vec<GpuRayStats> = read_back(ctx, &stats_read, n * 8, "ray stats")?;
        Ok(Frame {
            width: o.width,
            height: o.height,
            rgba: px.iter().flat_map(|p| p.to_le_bytes()).collect(),
            hits: h.iter().map(|h| Hit { t: h.t, triangle: h.triangle, u: h.u, v: h.v }).collect(),
            stats: st,
        })
    }
}
