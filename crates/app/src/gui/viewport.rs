//! The 3-D view: renders the scene through `gridrt-gpu` into a texture egui shows, on the
//! device eframe created (shared, not a second device). A frame is rendered only when something
//! changed, in tiles of about [`TILE_MS`] each submitted on its own, so the UI keeps running
//! while it renders; the frame's per-ray totals (cells, tests, hits) come back as 32 bytes
//! through `present.wgsl`.

use std::sync::{Arc, Mutex};

use eframe::egui;
use gridrt_gpu::layout::FrameTotals;
use gridrt_gpu::trace::tile_quantum;
use gridrt_gpu::{FrameSource, FrameTarget, GpuContext, GpuError, RenderOptions, Renderer, View};
use web_time::Instant;

/// The GPU side of the app.
pub struct Gpu {
    pub ctx: GpuContext,
    pub renderer: Renderer,
    pub egui: eframe::egui_wgpu::RenderState,
    /// To wake the UI when GPU work completes.
    pub ui: egui::Context,
    /// The grid build's pipelines (natively: builds run on a job thread on this device).
    pub builder: std::sync::Arc<gridrt_gpu::build::GridBuilder>,
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu").field("adapter", &self.ctx.adapter_name()).finish_non_exhaustive()
    }
}

impl Gpu {
    pub fn new(rs: &eframe::egui_wgpu::RenderState, ui: &egui::Context) -> Result<Gpu, GpuError> {
        let ctx = GpuContext::from_parts(rs.adapter.clone(), rs.device.clone(), rs.queue.clone());
        let renderer = Renderer::new(&ctx)?;
        let builder = std::sync::Arc::new(gridrt_gpu::build::GridBuilder::new(&ctx)?);
        Ok(Gpu { ctx, renderer, egui: rs.clone(), ui: ui.clone(), builder })
    }
}

/// What one finished frame measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameStats {
    pub width: u32,
    pub height: u32,
    /// Sum over the frame's tiles of submit → completion, wall clock.
    pub ms: f64,
    pub totals: FrameTotals,
    pub view: View,
    /// Traced on the CPU (`Settings::trace_on`), not on the GPU.
    pub on_cpu: bool,
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

/// A frame read back by [`Viewport::capture`]: width, height, RGBA8 pixels.
pub type Captured = Arc<Mutex<Option<Result<(u32, u32, Vec<u8>), String>>>>;

/// Set when a tile (or the totals readback) is done: the completion time, or the error.
type Done = Arc<Mutex<Option<Result<Instant, String>>>>;

/// Tiles are sized to take about this long, so that the UI (whose own drawing queues behind
/// them) and a browser's GPU watchdog never wait long.
const TILE_MS: f64 = 60.0;
/// GPU work submitted per UI wake-up.
const STEP_MS: f64 = 150.0;
/// Most tiles, and fewest pixels per UI wake-up, per frame. In a browser a tile's completion
/// is only seen at the next animation frame, after the page's own (software-rendered, slow)
/// paint, so the measured rate underestimates the GPU: fewer, larger tiles there.
#[cfg(not(target_arch = "wasm32"))]
const MAX_TILES: u32 = 128;
#[cfg(not(target_arch = "wasm32"))]
const MAX_WAKES: u32 = 128;
#[cfg(target_arch = "wasm32")]
const MAX_TILES: u32 = 8;
#[cfg(target_arch = "wasm32")]
const MAX_WAKES: u32 = 4;

/// A frame being rendered tile by tile.
#[derive(Debug)]
struct InFlight {
    opts: RenderOptions,
    /// Next pixel to render, and the frame's pixel count.
    next: u32,
    n: u32,
    /// Sum of the finished tiles' times (submit → done).
    gpu_ms: f64,
    /// The tile on the GPU: its pixel count, submit time and completion flag.
    tile: Option<(u32, Instant, Done)>,
    /// Set once the last tile's totals readback completed.
    totals: Option<Done>,
}

/// The render target, its egui texture and the frame in flight.
#[derive(Debug)]
pub struct Viewport {
    /// The target frames render into; egui shows the last completed one's texture.
    target: Option<FrameTarget>,
    texture: Option<egui::TextureId>,
    /// Size of the texture egui shows.
    shown: Option<(u32, u32)>,
    in_flight: Option<InFlight>,
    /// A frame asked for while another was in flight: it starts after the current tile.
    restart: Option<RenderOptions>,
    /// Pixels per millisecond of the last tile: sizes the next one.
    rate: f64,
    /// Natively, a thread waits for each submitted tile, so that its completion time is exact
    /// and the UI wakes at once (the browser runs the callbacks on its own).
    #[cfg(not(target_arch = "wasm32"))]
    waiter: Option<std::sync::mpsc::Sender<(wgpu::SubmissionIndex, Done)>>,
    pub last: Option<FrameStats>,
    /// Frames completed since start.
    pub frames_done: u64,
    /// Natively, frames traced on the CPU instead (`Settings::trace_on`).
    #[cfg(not(target_arch = "wasm32"))]
    cpu: CpuFrames,
}

/// A frame to trace on the CPU: what the GPU's frame reads, as the CPU holds it.
#[cfg(not(target_arch = "wasm32"))]
#[derive(Debug)]
pub struct CpuRequest {
    pub opts: RenderOptions,
    pub grid: Arc<gridrt_grid::AnyGrid>,
    pub tris: Arc<Vec<[glam::Vec3; 3]>>,
    pub bounds: gridrt_scene::Aabb,
}

/// The frame being traced on a job thread, and the one asked for after it (a newer request
/// replaces an older waiting one; the one being traced finishes).
#[cfg(not(target_arch = "wasm32"))]
#[derive(Debug, Default)]
struct CpuFrames {
    job: Option<super::jobs::Job<CpuFrame>>,
    next: Option<CpuRequest>,
}

/// A frame traced on the CPU: the image, its counts and its wall-clock time.
#[cfg(not(target_arch = "wasm32"))]
#[derive(Debug)]
pub struct CpuFrame {
    opts: RenderOptions,
    pub rgba: Vec<u8>,
    totals: FrameTotals,
    ms: f64,
}

impl Default for Viewport {
    fn default() -> Self {
        Viewport {
            target: None,
            texture: None,
            shown: None,
            in_flight: None,
            restart: None,
            rate: 1000.0,
            #[cfg(not(target_arch = "wasm32"))]
            waiter: None,
            last: None,
            frames_done: 0,
            #[cfg(not(target_arch = "wasm32"))]
            cpu: CpuFrames::default(),
        }
    }
}

/// The thread that waits for submitted tiles (native): it blocks on each submission, marks
/// it done with the time, and wakes the UI.
#[cfg(not(target_arch = "wasm32"))]
fn spawn_waiter(gpu: &Gpu) -> std::sync::mpsc::Sender<(wgpu::SubmissionIndex, Done)> {
    let (tx, rx) = std::sync::mpsc::channel::<(wgpu::SubmissionIndex, Done)>();
    let device = gpu.ctx.device.clone();
    let ui = gpu.ui.clone();
    std::thread::Builder::new()
        .name("gridrt tile waiter".into())
        .spawn(move || {
            for (index, done) in rx {
                let r = device
                    .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
                    .map(|_| Instant::now())
                    .map_err(|e| e.to_string());
                *done.lock().expect("tile lock") = Some(r);
                ui.request_repaint();
            }
        })
        .expect("spawning the tile waiter");
    tx
}

fn flag() -> (Done, Done) {
    let d: Done = Arc::new(Mutex::new(None));
    (d.clone(), d)
}

impl Viewport {
    /// The texture to draw, once a frame has been rendered into it.
    pub fn texture(&self) -> Option<egui::TextureId> {
        if self.frames_done > 0 { self.texture } else { None }
    }

    /// A frame is being rendered or waits to start.
    pub fn busy(&self) -> bool {
        #[cfg(not(target_arch = "wasm32"))]
        if self.cpu.job.is_some() || self.cpu.next.is_some() {
            return true;
        }
        self.in_flight.is_some() || self.restart.is_some()
    }

    /// Asks for a frame. One in flight is abandoned after its current tile (the camera or a
    /// setting changed, so its remaining tiles would be stale) unless it is about to finish.
    pub fn start(&mut self, opts: &RenderOptions) {
        // Natively, frames traced on the CPU are forgotten (one being traced finishes unseen).
        #[cfg(not(target_arch = "wasm32"))]
        {
            self.cpu = CpuFrames::default();
        }
        self.restart = Some(*opts);
    }

    /// Drops the frame in flight (after an error).
    pub fn cancel(&mut self) {
        self.in_flight = None;
        self.restart = None;
    }

    /// Shows the target's texture in egui (after its first complete frame at this size).
    fn show_target(&mut self, gpu: &Gpu) {
        let Some(t) = &self.target else { return };
        if self.shown == Some((t.width, t.height)) && self.texture.is_some() {
            return;
        }
        let view = t.display_view().expect("display target has a texture");
        let mut r = gpu.egui.renderer.write();
        match self.texture {
            Some(id) => r.update_egui_texture_from_wgpu_texture(&gpu.ctx.device, &view, wgpu::FilterMode::Linear, id),
            None => self.texture = Some(r.register_native_texture(&gpu.ctx.device, &view, wgpu::FilterMode::Linear)),
        }
        self.shown = Some((t.width, t.height));
    }

    /// Advances rendering, on the GPU (when `src` is on it) and (natively) on the CPU,
    /// whichever was asked for last: true when a frame completed.
    pub fn step(&mut self, gpu: &Gpu, src: Option<&FrameSource>) -> Result<bool, GpuError> {
        let on_gpu = match src {
            Some(src) => self.step_gpu(gpu, src)?,
            None => false,
        };
        #[cfg(not(target_arch = "wasm32"))]
        if self.step_cpu(gpu)? {
            return Ok(true);
        }
        Ok(on_gpu)
    }

    /// Collects a finished tile, finishes the frame, starts a requested one, submits the next
    /// tile. Returns true when a frame completed.
    fn step_gpu(&mut self, gpu: &Gpu, src: &FrameSource) -> Result<bool, GpuError> {
        #[cfg(not(target_arch = "wasm32"))]
        let _ = gpu.ctx.device.poll(wgpu::PollType::Poll);
        let mut completed = false;
        if let Some(f) = &mut self.in_flight {
            if let Some((count, started, done)) = &f.tile {
                let Some(result) = done.lock().expect("tile lock").take() else { return Ok(false) };
                let finished = result.map_err(|e| GpuError::Readback { what: "frame tile", detail: e })?;
                let ms = finished.duration_since(*started).as_secs_f64() * 1e3;
                self.rate = *count as f64 / ms.max(0.1);
                f.gpu_ms += ms;
                f.tile = None;
            }
            if let Some(totals) = &f.totals {
                let Some(result) = totals.lock().expect("totals lock").take() else { return Ok(false) };
                result.map_err(|e| GpuError::Readback { what: "frame totals", detail: e })?;
                let f = self.in_flight.take().expect("in flight");
                let target = self.target.as_ref().expect("target");
                self.last = Some(FrameStats {
                    width: target.width,
                    height: target.height,
                    ms: f.gpu_ms,
                    totals: target.take_totals()?,
                    view: f.opts.view,
                    on_cpu: false,
                });
                self.frames_done += 1;
                completed = true;
                self.show_target(gpu);
            }
        }
        if let Some(opts) = self.restart.take() {
            // Nothing of ours is on the GPU now: the target may be replaced.
            if self.target.as_ref().is_none_or(|t| (t.width, t.height) != (opts.width, opts.height)) {
                self.target = Some(FrameTarget::new(&gpu.ctx, opts.width, opts.height, true)?);
            }
            let n = opts.width * opts.height;
            self.in_flight = Some(InFlight { opts, next: 0, n, gpu_ms: 0.0, tile: None, totals: None });
        }
        let Some(f) = &mut self.in_flight else { return Ok(completed) };
        if f.next >= f.n {
            // Cut short (render_blocking stops after the tile on the GPU).
            self.in_flight = None;
            return Ok(completed);
        }
        let target = self.target.as_ref().expect("target");
        let q = tile_quantum(&gpu.ctx);
        // Tiles of ~TILE_MS, at most ~128 a frame; several per UI wake-up, up to STEP_MS of
        // work, since each wake-up repaints the UI (costly on a software adapter).
        let floor = (f.n / MAX_TILES).max(q) as f64;
        let tile = ((self.rate * TILE_MS).clamp(floor, f.n as f64) as u32 / q * q).max(q).min(target.tile_capacity());
        let budget = (self.rate * STEP_MS).max(tile as f64).max((f.n / MAX_WAKES) as f64) as u64;
        let started = Instant::now();
        let mut count = 0u32;
        let mut index = None;
        while f.next < f.n && (count as u64) < budget {
            let c = tile.min(f.n - f.next);
            let mut enc =
                gpu.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("app tile") });
            gpu.renderer.encode_tile(&gpu.ctx, &mut enc, src, &f.opts, target, f.next..f.next + c)?;
            // Each tile's uniforms are written before its own submission, so back-to-back
            // submissions see their own values (queue writes are ordered with submissions).
            index = Some(gpu.ctx.queue.submit([enc.finish()]));
            f.next += c;
            count += c;
        }
        let index = index.expect("at least one tile");
        let (done, d) = flag();
        #[cfg(not(target_arch = "wasm32"))]
        {
            let waiter = self.waiter.get_or_insert_with(|| spawn_waiter(gpu));
            let _ = waiter.send((index, d));
        }
        #[cfg(target_arch = "wasm32")]
        {
            let _ = index;
            gpu.ctx.queue.on_submitted_work_done(move || *d.lock().expect("tile lock") = Some(Ok(Instant::now())));
        }
        f.tile = Some((count, started, done));
        if f.next == f.n {
            let (totals, t) = flag();
            let ui = gpu.ui.clone();
            target.totals_read.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                *t.lock().expect("totals lock") = Some(r.map(|()| Instant::now()).map_err(|e| e.to_string()));
                // The frame is done: wake the UI to show it (it does not repaint while waiting).
                ui.request_repaint();
            });
            f.totals = Some(totals);
        }
        Ok(completed)
    }

    /// Reads the last finished frame back (RGBA8) from the display texture, which holds every
    /// tile (the per-pixel buffers hold only the last one): `None` while a frame is in flight or
    /// before the first one. The result arrives asynchronously in the returned slot.
    pub fn capture(&self, gpu: &Gpu) -> Option<Captured> {
        let t = self.target.as_ref()?;
        let texture = t.texture.as_ref()?;
        if self.frames_done == 0 || self.busy() {
            return None;
        }
        let (w, h) = (t.width, t.height);
        // Texture rows are copied at a 256-byte pitch; the padding is dropped after mapping.
        let row = w as usize * 4;
        let pitch = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as usize);
        let dev = &gpu.ctx.device;
        let buf = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame capture readback"),
            size: (pitch * h as usize) as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame capture") });
        enc.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buf,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(pitch as u32),
                    rows_per_image: None,
                },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        gpu.ctx.queue.submit([enc.finish()]);
        let slot: Captured = Arc::new(Mutex::new(None));
        let (out, b, ui) = (slot.clone(), buf.clone(), gpu.ui.clone());
        buf.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let result = r.map_err(|e| e.to_string()).and_then(|()| {
                let view = b.slice(..).get_mapped_range().map_err(|e| e.to_string())?;
                let rgba: Vec<u8> = view.chunks_exact(pitch).flat_map(|r| &r[..row]).copied().collect();
                drop(view);
                b.unmap();
                Ok((w, h, rgba))
            });
            *out.lock().expect("capture lock") = Some(result);
            ui.request_repaint();
        });
        Some(slot)
    }

    /// Renders a whole frame, blocking until it is done (the cost-model measurement times
    /// frames). Returns its milliseconds, wall clock.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn render_blocking(&mut self, gpu: &Gpu, src: &FrameSource, opts: &RenderOptions) -> Result<f64, GpuError> {
        // Finish (or abandon) what is in flight first.
        self.restart = None;
        while self.in_flight.is_some() {
            if let Some(f) = &mut self.in_flight
                && f.tile.is_none()
                && f.totals.is_none()
            {
                self.in_flight = None;
                break;
            }
            let _ = gpu.ctx.device.poll(wgpu::PollType::wait_indefinitely());
            if let Some(f) = &mut self.in_flight {
                // Stop after the tile on the GPU: do not submit the rest.
                f.n = f.next;
            }
            self.step(gpu, Some(src))?;
        }
        self.start(opts);
        let started = Instant::now();
        loop {
            if self.step(gpu, Some(src))? {
                return Ok(started.elapsed().as_secs_f64() * 1e3);
            }
            let _ = gpu.ctx.device.poll(wgpu::PollType::wait_indefinitely());
        }
    }
}

/// Frames traced on the CPU (native): the render kernels' CPU ports on every core
/// (`crate::lab::frame::cpu_frame`, as `gridrt render --backend cpu`), the image written into
/// the display texture the GPU's frames go to.
#[cfg(not(target_arch = "wasm32"))]
impl Viewport {
    /// Asks for a frame traced on the CPU; it starts when the one being traced is done. A GPU
    /// frame in flight is dropped.
    pub fn start_cpu(&mut self, req: CpuRequest) {
        self.cancel();
        self.cpu.next = Some(req);
    }

    /// Shows a frame the CPU finished and starts the next one. Returns true when a frame
    /// completed.
    fn step_cpu(&mut self, gpu: &Gpu) -> Result<bool, GpuError> {
        let mut completed = false;
        if let Some(job) = &mut self.cpu.job
            && let Some(result) = job.poll()
        {
            self.cpu.job = None;
            let f = result.map_err(|detail| GpuError::Readback { what: "a frame traced on the CPU", detail })?;
            let (w, h) = (f.opts.width, f.opts.height);
            if self.target.as_ref().is_none_or(|t| (t.width, t.height) != (w, h)) {
                self.target = Some(FrameTarget::new(&gpu.ctx, w, h, true)?);
            }
            let target = self.target.as_ref().expect("target");
            target.write_image(&gpu.ctx, &f.rgba)?;
            self.last =
                Some(FrameStats { width: w, height: h, ms: f.ms, totals: f.totals, view: f.opts.view, on_cpu: true });
            self.frames_done += 1;
            completed = true;
            self.show_target(gpu);
        }
        if self.cpu.job.is_none()
            && let Some(req) = self.cpu.next.take()
        {
            self.cpu.job =
                Some(super::jobs::Job::spawn("tracing a frame on the CPU", &gpu.ui, move || trace_on_cpu(req)));
        }
        Ok(completed)
    }
}

/// Traces and shades one frame on the CPU: coherent packets when the settings ask for them
/// (single rays for the heatmaps, which need per-ray counts).
#[cfg(not(target_arch = "wasm32"))]
pub fn trace_on_cpu(req: CpuRequest) -> CpuFrame {
    let started = Instant::now();
    let o = req.opts;
    let primary = gridrt_gpu::cpu::camera_rays(&gridrt_gpu::cpu::gpu_camera(&o.camera, o.width, o.height));
    let packets = (o.packets && !o.view.is_heatmap())
        .then_some(gridrt_grid::PacketOptions { tile: gridrt_gpu::Kernel::PACKET_EDGE, mailbox: o.mailbox });
    let r = crate::lab::frame::cpu_frame(&req.grid, &req.tris, &req.bounds, &o, &primary, packets);
    let rays = primary.len() as u64;
    let hits = r.hits.iter().filter(|h| h.is_hit()).count() as u32;
    let split = |v: u64| [v as u32, (v >> 32) as u32];
    let totals = FrameTotals {
        cells: split((r.cells_per_ray * rays as f64).round() as u64),
        tests: split((r.tests_per_ray * rays as f64).round() as u64),
        hits,
        rays: rays as u32,
        pad: [0; 2],
    };
    CpuFrame { opts: o, rgba: r.rgba, totals, ms: started.elapsed().as_secs_f64() * 1e3 }
}
