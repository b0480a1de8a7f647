//! The one assembly point of the GPU side: a device with a scene uploaded, the trace pass, and
//! the render pass (made on first use). The command line, the experiments, the benchmark and
//! the tests start from it; the app assembles the same parts on eframe's device
//! (crates/app/src/gui/viewport.rs), because it renders into textures egui shows.

use std::sync::OnceLock;

use glam::Vec3;
use gridrt_grid::{AnyGrid, RayStats, TraceOptions};
use gridrt_scene::{Aabb, Hit, Ray};

use crate::context::{GpuContext, GpuError};
use crate::render::{Frame, FrameSource, RenderOptions, Renderer};
use crate::trace::Tracer;
use crate::upload::{GpuScene, GpuStructure};

/// A scene on a device, ready to trace and render through any structure built over it.
#[derive(Debug)]
pub struct GpuSession<'a> {
    pub ctx: &'a GpuContext,
    pub scene: GpuScene,
    /// The scene's bounds (the render pass places its light and depth range by them).
    pub bounds: Aabb,
    pub tracer: Tracer,
    renderer: OnceLock<Renderer>,
}

impl<'a> GpuSession<'a> {
    /// Uploads the triangles `tris` (bounded by `bounds`) to `ctx`.
    pub fn new(ctx: &'a GpuContext, tris: &[[Vec3; 3]], bounds: Aabb) -> Result<GpuSession<'a>, GpuError> {
        Ok(GpuSession {
            ctx,
            scene: GpuScene::new(ctx, tris)?,
            bounds,
            tracer: Tracer::new(),
            renderer: OnceLock::new(),
        })
    }

    /// Replaces the session's triangles with `tris` (a new pose of the same scene, within the
    /// same bounds); the trace and render pipelines are kept.
    pub fn set_triangles(&mut self, tris: &[[Vec3; 3]]) -> Result<(), GpuError> {
        self.scene = GpuScene::new(self.ctx, tris)?;
        Ok(())
    }

    /// Uploads a structure built over the session's triangles.
    pub fn upload(&self, grid: &AnyGrid) -> Result<GpuStructure, GpuError> {
        GpuStructure::new(self.ctx, grid)
    }

    /// Closest (or any) hits and per-ray counters of `rays` through `s` (see [`Tracer::trace`]).
    pub fn trace(
        &self,
        s: &GpuStructure,
        rays: &[Ray],
        opts: TraceOptions,
    ) -> Result<(Vec<Hit>, Vec<RayStats>), GpuError> {
        self.tracer.trace(self.ctx, &self.scene, s, rays, opts)
    }

    /// [`GpuSession::trace`] for the rays of a row-major image `width` pixels wide, in 8×8
    /// packets where the structure has a packet kernel (see [`Tracer::trace_image`]).
    pub fn trace_image(
        &self,
        s: &GpuStructure,
        rays: &[Ray],
        width: u32,
        opts: TraceOptions,
    ) -> Result<(Vec<Hit>, Vec<RayStats>), GpuError> {
        self.tracer.trace_image(self.ctx, &self.scene, s, rays, width, opts)
    }

    /// Renders one image through `s` and reads it back (see [`Renderer::render`]).
    pub fn render(&self, s: &GpuStructure, opts: &RenderOptions) -> Result<Frame, GpuError> {
        self.renderer()?.render(self.ctx, &self.source(s), opts)
    }

    /// What a frame through `s` is drawn from.
    pub fn source<'s>(&'s self, s: &'s GpuStructure) -> FrameSource<'s> {
        FrameSource { scene: &self.scene, structure: s, bounds: &self.bounds }
    }

    /// The render pass, its pipelines created by the first call.
    pub fn renderer(&self) -> Result<&Renderer, GpuError> {
        if let Some(r) = self.renderer.get() {
            return Ok(r);
        }
        let r = Renderer::new(self.ctx)?;
        Ok(self.renderer.get_or_init(|| r))
    }
}
