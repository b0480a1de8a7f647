//! The 3-D view: renders the scene through `gridrt-gpu` into a texture egui shows, on the
//! device eframe created (shared, not a second device). One frame is in flight at a time; the
//! UI keeps running while it is, and the frame's per-ray totals (cells, tests, hits) come back
//! as 32 bytes through `present.wgsl`. A frame is rendered only when something changed.

use std::sync::{Arc, Mutex};

use eframe::egui;
use gridrt_gpu::layout::FrameTotals;
use gridrt_gpu::upload::{GpuScene, GpuStructure};
use gridrt_gpu::{FrameTarget, GpuContext, GpuError, RenderOptions, Renderer, View};
use gridrt_scene::Aabb;
use web_time::Instant;

/// The GPU side of the app.
pub struct Gpu {
    pub ctx: GpuContext,
    pub renderer: Renderer,
    pub egui: eframe::egui_wgpu::RenderState,
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu").field("adapter", &self.ctx.adapter_name()).finish_non_exhaustive()
    }
}

impl Gpu {
    pub fn new(rs: &eframe::egui_wgpu::RenderState) -> Result<Gpu, GpuError> {
        let ctx = GpuContext::from_parts(rs.adapter.clone(), rs.device.clone(), rs.queue.clone());
        let renderer = Renderer::new(&ctx)?;
        Ok(Gpu { ctx, renderer, egui: rs.clone() })
    }
}

/// What one finished frame measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameStats {
    pub width: u32,
    pub height: u32,
    /// Submit to completion, wall clock.
    pub ms: f64,
    pub totals: FrameTotals,
    pub view: View,
}

impl FrameStats {
    /// Rays traced: primary, plus one shadow ray per hit in the shaded view.
    pub fn rays(&self) -> u64 {
        self.totals.rays as u64 + if self.view == View::Shaded { self.totals.hits as u64 } else { 0 }
    }
    pub fn mrays_per_s(&self) -> f64 {
        self.rays() as f64 / (self.ms.max(1e-6) * 1e3)
    }
    pub fn mean_cells(&self) -> f64 {
        self.totals.cells() as f64 / self.totals.rays.max(1) as f64
    }
    pub fn mean_tests(&self) -> f64 {
        self.totals.tests() as f64 / self.totals.rays.max(1) as f64
    }
}

type Done = Arc<Mutex<Option<Result<(), String>>>>;

#[derive(Debug)]
struct InFlight {
    started: Instant,
    done: Done,
    view: View,
}

/// The render target, its egui texture and the frame in flight.
#[derive(Debug, Default)]
pub struct Viewport {
    target: Option<FrameTarget>,
    texture: Option<egui::TextureId>,
    in_flight: Option<InFlight>,
    /// Something changed since the last submitted frame.
    pub dirty: bool,
    pub last: Option<FrameStats>,
    /// Frames completed since start.
    pub frames_done: u64,
    pub error: Option<String>,
}

impl Viewport {
    /// The texture to draw, once a frame has been rendered into it.
    pub fn texture(&self) -> Option<egui::TextureId> {
        if self.frames_done > 0 { self.texture } else { None }
    }

    pub fn busy(&self) -> bool {
        self.in_flight.is_some()
    }

    /// Makes the target `w`×`h`, re-registering the texture with egui when it changes.
    fn ensure_target(&mut self, gpu: &Gpu, w: u32, h: u32) -> Result<(), GpuError> {
        if self.target.as_ref().is_some_and(|t| (t.width, t.height) == (w, h)) {
            return Ok(());
        }
        let target = FrameTarget::new(&gpu.ctx, w, h, true)?;
        let view = target.display_view().expect("display target has a texture");
        let mut r = gpu.egui.renderer.write();
        match self.texture {
            Some(id) => r.update_egui_texture_from_wgpu_texture(&gpu.ctx.device, &view, wgpu::FilterMode::Linear, id),
            None => self.texture = Some(r.register_native_texture(&gpu.ctx.device, &view, wgpu::FilterMode::Linear)),
        }
        self.target = Some(target);
        Ok(())
    }

    /// Collects a finished frame, if any. Returns true when one finished.
    pub fn poll(&mut self, gpu: &Gpu) -> bool {
        let Some(f) = &self.in_flight else { return false };
        #[cfg(not(target_arch = "wasm32"))]
        let _ = gpu.ctx.device.poll(wgpu::PollType::Poll);
        let Some(result) = f.done.lock().expect("frame lock").take() else { return false };
        let f = self.in_flight.take().expect("in flight");
        let target = self.target.as_ref().expect("a frame in flight has a target");
        match result.and_then(|()| target.take_totals().map_err(|e| e.to_string())) {
            Ok(totals) => {
                self.last = Some(FrameStats {
                    width: target.width,
                    height: target.height,
                    ms: f.started.elapsed().as_secs_f64() * 1e3,
                    totals,
                    view: f.view,
                });
                self.frames_done += 1;
                self.error = None;
            }
            Err(e) => self.error = Some(format!("frame failed: {e}")),
        }
        true
    }

    /// Submits a frame if none is in flight. `opts.width/height` set the target size.
    pub fn submit(
        &mut self,
        gpu: &Gpu,
        scene: &GpuScene,
        s: &GpuStructure,
        bounds: &Aabb,
        opts: &RenderOptions,
    ) -> Result<bool, GpuError> {
        if self.in_flight.is_some() {
            return Ok(false);
        }
        self.ensure_target(gpu, opts.width, opts.height)?;
        let target = self.target.as_ref().expect("target");
        let mut enc =
            gpu.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("app frame") });
        gpu.renderer.encode(&gpu.ctx, &mut enc, scene, s, bounds, opts, target)?;
        let started = Instant::now();
        gpu.ctx.queue.submit([enc.finish()]);
        let done: Done = Arc::new(Mutex::new(None));
        let d = done.clone();
        target.totals_read.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            *d.lock().expect("frame lock") = Some(r.map_err(|e| e.to_string()));
        });
        self.in_flight = Some(InFlight { started, done, view: opts.view });
        self.dirty = false;
        Ok(true)
    }

    /// Blocks until the frame in flight is done (the cost-model measurement times frames).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn wait(&mut self, gpu: &Gpu) {
        if self.in_flight.is_some() {
            let _ = gpu.ctx.device.poll(wgpu::PollType::wait_indefinitely());
            self.poll(gpu);
        }
    }
}
