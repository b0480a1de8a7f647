//! The desktop (and browser) app: eframe on wgpu, sharing eframe's device with `gridrt-gpu`.
//!
//! Data flows one way, as in the library: a scene (loaded off the UI thread) → a structure
//! (built off the UI thread) → GPU buffers → a rendered texture and its stats. The UI edits
//! [`Settings`]; when the wanted structure differs from the built one a rebuild starts (the
//! previous structure stays on screen meanwhile), and when anything the image depends on
//! changes a frame is rendered.

pub mod cost_plot;
pub mod explainer;
pub mod hook;
pub mod jobs;
pub mod orbit;
pub mod panels;
pub mod settings;
pub mod viewport;
#[cfg(target_arch = "wasm32")]
pub mod web;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use eframe::egui::{self, Key, PointerButton, Sense, Vec2};
use gridrt_gpu::upload::{GpuScene, GpuStructure};
use gridrt_gpu::{RenderOptions, View};
use gridrt_grid::{GridConfig, GridKind, Resolution};
use gridrt_scene::Camera;
use web_time::Instant;

use crate::cli::AppArgs;
use hook::{CapturedFrame, Hook, HookCommand, HookStats};
use jobs::{Built, Job, LoadedScene, SceneSource};
use orbit::Orbit;
use settings::Settings;
use viewport::{Gpu, Viewport};

/// How a smoke run (`--screenshot`) ended: `Ok(message)` or `Err(reason)`.
pub type SmokeStatus = Arc<Mutex<Option<Result<String, String>>>>;

/// `--screenshot out.png --frames N`: render N frames, save the window, exit.
#[derive(Debug)]
struct Smoke {
    path: PathBuf,
    frames: u32,
    requested: bool,
    shot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
    status: SmokeStatus,
    started: Instant,
}

/// Seconds a smoke run may take before it gives up.
const SMOKE_TIMEOUT_S: f64 = 600.0;

#[derive(Debug)]
struct SceneState {
    loaded: LoadedScene,
    gpu: Option<GpuScene>,
    generation: u64,
}

#[derive(Debug)]
struct BuiltState {
    built: Built,
    gpu: Option<GpuStructure>,
    /// Changes with every new structure (part of the render key).
    id: u64,
}

/// Everything a frame depends on: a new frame is rendered when this changes.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RenderKey {
    camera: Camera,
    view: View,
    traversal: gridrt_grid::Traversal,
    mailbox: bool,
    heat_max: f32,
    size: [u32; 2],
    structure: u64,
}

pub struct GridrtApp {
    settings: Settings,
    smoke: Option<Smoke>,
    gpu: Option<Gpu>,
    gpu_error: Option<String>,
    scene: Option<SceneState>,
    scene_generation: u64,
    scene_job: Option<Job<Result<LoadedScene, String>>>,
    build_job: Option<Job<Result<Built, String>>>,
    built: Option<BuiltState>,
    built_counter: u64,
    orbit: Orbit,
    viewport: Viewport,
    last_key: Option<RenderKey>,
    /// A load or build error, shown until dismissed; the previous scene stays.
    error: Option<String>,
    build_error: Option<(GridConfig, String)>,
    measurement: cost_plot::Measurement,
    measure_job: Option<Job<Result<Built, String>>>,
    /// `--camera`: used for the first scene instead of framing it.
    initial_camera: Option<Camera>,
    /// When the camera last moved, and the resolution factor used while it moves.
    last_interaction: Option<Instant>,
    interactive_factor: f32,
    factor_frame: u64,
    /// `--measure`: start the cost-model measurement when a structure with a cost curve is up.
    measure_at_start: bool,
    /// A file dropped or picked in the browser, while its bytes are read.
    #[cfg(target_arch = "wasm32")]
    dropped: Option<std::sync::mpsc::Receiver<Result<(String, Vec<u8>), String>>>,
    /// The test hook (`window.gridrt` in the browser).
    hook: Hook,
    /// A fixed render size set through the hook (instead of following the window).
    frame_size: Option<[u32; 2]>,
    /// Captures asked for through the hook, and the one being read back.
    captures: std::collections::VecDeque<u64>,
    capture: Option<(u64, viewport::Captured)>,
    /// Set by `central` when the frame on screen (or in flight) is for the current settings.
    frame_current: bool,
    /// Milliseconds from start to the first frame (the page's clock in a browser).
    first_frame_ms: Option<f64>,
    worker_builds: u64,
    #[cfg_attr(target_arch = "wasm32", allow(dead_code))]
    started: Instant,
}

/// While the camera moves, frames slower than this are rendered at a lower resolution; the
/// full resolution follows when the camera rests.
const INTERACTIVE_FRAME_MS: f64 = 60.0;
/// How long after the last camera move the view counts as resting.
const REST_AFTER_S: f64 = 0.3;

impl std::fmt::Debug for GridrtApp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GridrtApp").field("settings", &self.settings).finish_non_exhaustive()
    }
}

impl GridrtApp {
    pub fn new(cc: &eframe::CreationContext<'_>, args: AppArgs, status: SmokeStatus) -> GridrtApp {
        let smoke = args.screenshot.clone().map(|path| Smoke {
            path,
            frames: args.frames.max(1),
            requested: false,
            shot: Default::default(),
            status,
            started: Instant::now(),
        });
        // A smoke run ignores saved settings so that it is reproducible.
        let mut settings: Settings = match (&smoke, cc.storage) {
            (None, Some(st)) => eframe::get_value(st, settings::STORAGE_KEY).unwrap_or_default(),
            _ => Settings::default(),
        };
        if let Some(k) = args.grid {
            settings.grid.kind = k;
        }
        if let Some(v) = &args.view {
            settings.view = v.name().into();
        }
        if let Some(t) = args.traversal {
            settings.traversal = t;
        }
        if smoke.is_some() {
            settings.render_scale = 1.0;
        }
        if let Some(r) = args.render_scale {
            settings.render_scale = r.clamp(0.05, 1.0);
        }
        if args.measure {
            settings.show_cost_plot = true;
        }
        for w in &args.open {
            match w {
                crate::cli::AppWindow::CostModel => settings.show_cost_plot = true,
                crate::cli::AppWindow::Explainer => settings.show_explainer = true,
            }
        }
        let (gpu, gpu_error) = match cc.wgpu_render_state.as_ref() {
            Some(rs) => match Gpu::new(rs, &cc.egui_ctx) {
                Ok(g) => (Some(g), None),
                Err(e) => (None, Some(format!("GPU setup failed: {e}"))),
            },
            None => (None, Some("eframe started without a wgpu device".to_string())),
        };
        let mut app = GridrtApp {
            settings,
            smoke,
            gpu,
            gpu_error,
            scene: None,
            scene_generation: 0,
            scene_job: None,
            build_job: None,
            built: None,
            built_counter: 0,
            orbit: Orbit::fit(&gridrt_scene::Aabb::from_points(&[glam::Vec3::ZERO, glam::Vec3::ONE]), 1.5),
            viewport: Viewport::default(),
            last_key: None,
            error: None,
            build_error: None,
            measurement: Default::default(),
            measure_job: None,
            initial_camera: args.camera,
            last_interaction: None,
            interactive_factor: 1.0,
            factor_frame: 0,
            measure_at_start: args.measure,
            #[cfg(target_arch = "wasm32")]
            dropped: None,
            hook: Default::default(),
            frame_size: args.frame_size.map(|(w, h)| [w, h]),
            captures: Default::default(),
            capture: None,
            frame_current: false,
            first_frame_ms: None,
            worker_builds: 0,
            started: Instant::now(),
        };
        app.hook.lock().expect("hook lock").repaint = Some(cc.egui_ctx.clone());
        let source = args.scene.map_or(SceneSource::Default, SceneSource::Path);
        app.open(&cc.egui_ctx, source);
        app
    }

    /// Starts loading a scene; the current one stays until the new one is ready.
    fn open(&mut self, ctx: &egui::Context, source: SceneSource) {
        let label = source.label();
        self.scene_job = Some(Job::spawn(format!("loading {label}"), ctx, move || jobs::load_scene(&source)));
    }

    fn view(&self) -> View {
        self.settings.view.parse().unwrap_or_default()
    }

    fn fail_smoke(&mut self, ctx: &egui::Context, why: String) {
        if let Some(s) = &self.smoke {
            *s.status.lock().expect("smoke status") = Some(Err(why));
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
    }

    /// Collects finished jobs and starts the builds the settings ask for.
    fn poll_jobs(&mut self, ctx: &egui::Context) {
        if let Some(job) = &mut self.scene_job
            && let Some(r) = job.poll()
        {
            self.scene_job = None;
            match r.and_then(|r| r) {
                Ok(loaded) => {
                    if let Err(e) = self.set_scene(loaded) {
                        self.error = Some(e.clone());
                        self.fail_smoke(ctx, e);
                    }
                }
                Err(e) => {
                    self.error = Some(e.clone());
                    self.fail_smoke(ctx, e);
                }
            }
        }
        if let Some(job) = &mut self.build_job
            && let Some(r) = job.poll()
        {
            self.build_job = None;
            match r.and_then(|r| r) {
                Ok(b) if Some(b.scene_generation) == self.scene.as_ref().map(|s| s.generation) => self.set_built(b),
                Ok(_) => {} // built for a scene that has been replaced since
                Err(e) => {
                    self.build_error = Some((self.settings.grid, e.clone()));
                    self.fail_smoke(ctx, e);
                }
            }
        }
        // Rebuild when the wanted structure differs from the built one (one build at a time;
        // the newest settings win when it finishes).
        if self.build_job.is_none()
            && let Some(scene) = &self.scene
        {
            let want = self.settings.grid;
            let have = self.built.as_ref().map(|b| (b.built.scene_generation, b.built.config));
            let failed = self.build_error.as_ref().is_some_and(|(c, _)| *c == want);
            if have != Some((scene.generation, want)) && !failed {
                self.build_error = None;
                let tris = scene.loaded.tris.clone();
                let generation = scene.generation;
                self.build_job = Some(jobs::spawn_build(ctx, tris, want, generation));
            }
        }
        if self.measure_at_start && self.last_key.is_some() && self.built.is_some() && self.build_job.is_none() {
            self.measure_at_start = false;
            if !self.start_measurement() {
                let why = "--measure: the structure has no sampled cost curve (use a flat or macrocell grid with auto resolution)";
                self.error = Some(why.into());
                self.fail_smoke(ctx, why.into());
            }
        }
        self.poll_measurement(ctx);
    }

    /// Makes `loaded` the current scene; when its GPU upload fails the previous scene stays and
    /// the error is returned.
    fn set_scene(&mut self, loaded: LoadedScene) -> Result<(), String> {
        let gpu_scene = match &self.gpu {
            Some(g) => Some(
                GpuScene::new(&g.ctx, &loaded.tris)
                    .and_then(|s| g.ctx.check_device().map(|()| s))
                    .map_err(|e| format!("{}: {e} (the previous scene stays)", loaded.name))?,
            ),
            None => None,
        };
        self.scene_generation += 1;
        let aspect = self.last_key.map_or(1.0, |k| k.size[0] as f32 / k.size[1].max(1) as f32);
        self.orbit = match self.initial_camera.take() {
            Some(cam) => Orbit::from_camera(&cam, &loaded.bounds),
            None => Orbit::fit(&loaded.bounds, aspect),
        };
        self.scene = Some(SceneState { loaded, gpu: gpu_scene, generation: self.scene_generation });
        self.measurement = Default::default();
        self.build_error = None;
        Ok(())
    }

    fn set_built(&mut self, built: Built) {
        self.worker_builds += u64::from(built.in_worker);
        let gpu = match &self.gpu {
            Some(g) => match GpuStructure::new(&g.ctx, &built.grid).and_then(|s| g.ctx.check_device().map(|()| s)) {
                Ok(s) => Some(s),
                Err(e) => {
                    // The previous structure stays on screen; this configuration is not retried.
                    self.build_error = Some((
                        built.config,
                        format!("uploading the {} grid: {e} (the previous one stays)", built.config.kind),
                    ));
                    return;
                }
            },
            None => None,
        };
        self.built_counter += 1;
        self.built = Some(BuiltState { built, gpu, id: self.built_counter });
    }

    /// Starts timing a flat grid at each resolution the cost model sampled (false when the
    /// current structure has no sampled curve).
    fn start_measurement(&mut self) -> bool {
        let Some(c) = self.built.as_ref().and_then(|b| b.built.report.resolution_choice.as_ref()) else { return false };
        if c.curve.is_empty() {
            return false;
        }
        self.measurement = cost_plot::Measurement {
            pending: c.curve.iter().map(|s| s.resolution).collect(),
            results: Vec::new(),
            total: c.curve.len(),
        };
        true
    }

    /// The cost-plot measurement: builds the next sampled resolution off the UI thread, then
    /// renders it once, timed.
    fn poll_measurement(&mut self, ctx: &egui::Context) {
        if let Some(job) = &mut self.measure_job
            && let Some(r) = job.poll()
        {
            self.measure_job = None;
            match r.and_then(|r| r) {
                Ok(b) => self.time_frame(&b),
                Err(e) => {
                    self.error = Some(e);
                    self.measurement.pending.clear();
                }
            }
        }
        if self.measure_job.is_none()
            && !self.measurement.pending.is_empty()
            && let Some(scene) = &self.scene
        {
            let res = self.measurement.pending[0];
            let cfg =
                GridConfig { kind: GridKind::Flat, resolution: Some(Resolution::Explicit(res)), ..self.settings.grid };
            let tris = scene.loaded.tris.clone();
            let generation = scene.generation;
            self.measure_job =
                Some(Job::spawn("measuring", ctx, move || jobs::build_structure(&tris, &cfg, generation)));
        }
    }

    #[cfg(not(target_arch = "wasm32"))]
    fn time_frame(&mut self, b: &Built) {
        let res = self.measurement.pending.remove(0);
        let (Some(gpu), Some(scene), Some(key)) = (&self.gpu, &self.scene, self.last_key) else { return };
        let Some(gs) = &scene.gpu else { return };
        let s = match GpuStructure::new(&gpu.ctx, &b.grid) {
            Ok(s) => s,
            Err(e) => {
                self.error = Some(e.to_string());
                return;
            }
        };
        let opts = self.render_options(key.camera, key.size);
        match self.viewport.render_blocking(gpu, gs, &s, &scene.loaded.bounds, &opts) {
            Ok(ms) => {
                let m = (res[0] as f64 * res[1] as f64 * res[2] as f64).cbrt();
                self.measurement.results.push((m, ms));
            }
            Err(e) => {
                self.viewport.cancel();
                self.error = Some(e.to_string());
            }
        }
        // The measured frame replaced the image: render the real structure again.
        self.last_key = None;
    }

    #[cfg(target_arch = "wasm32")]
    fn time_frame(&mut self, _b: &Built) {
        // Timing needs a blocking wait, which the browser does not allow.
        self.measurement.pending.clear();
        self.error = Some("frame-time measurement is not available in the browser".into());
    }

    fn render_options(&self, camera: Camera, size: [u32; 2]) -> RenderOptions {
        RenderOptions {
            width: size[0],
            height: size[1],
            camera,
            view: self.view(),
            traversal: self.settings.traversal,
            mailbox: self.settings.mailbox,
            heat_max: self.settings.heat_max,
        }
    }

    fn menu(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                #[cfg(not(target_arch = "wasm32"))]
                if ui.button("Open…").clicked() {
                    if let Some(p) = rfd::FileDialog::new().add_filter("glTF", &["glb", "gltf"]).pick_file() {
                        self.open(ui.ctx(), SceneSource::Path(p));
                    }
                    ui.close();
                }
                // In the browser the picker is asynchronous: its bytes arrive like a dropped file's.
                #[cfg(target_arch = "wasm32")]
                if ui.button("Open…").clicked() {
                    let (tx, rx) = std::sync::mpsc::channel();
                    let ui_ctx = ui.ctx().clone();
                    wasm_bindgen_futures::spawn_local(async move {
                        let picked = rfd::AsyncFileDialog::new().add_filter("glTF", &["glb", "gltf"]).pick_file().await;
                        if let Some(f) = picked {
                            let _ = tx.send(Ok((f.file_name(), f.read().await)));
                            ui_ctx.request_repaint();
                        }
                    });
                    self.dropped = Some(rx);
                    ui.close();
                }
                if ui.button("Default scene").clicked() {
                    self.open(ui.ctx(), SceneSource::Default);
                    ui.close();
                }
                #[cfg(not(target_arch = "wasm32"))]
                if ui.button("Save image…").clicked() {
                    self.save_image();
                    ui.close();
                }
                #[cfg(not(target_arch = "wasm32"))]
                if ui.button("Quit").clicked() {
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
            ui.menu_button("Windows", |ui| {
                ui.checkbox(&mut self.settings.show_cost_plot, "Cost model");
                ui.checkbox(&mut self.settings.show_explainer, "Traversal explainer");
            });
            if ui.button("Reset camera").clicked() {
                self.reset_camera();
            }
            ui.label("drag: orbit · right/shift-drag: pan · wheel: zoom · F: reset · drop a .glb to open");
        });
    }

    fn reset_camera(&mut self) {
        if let Some(s) = &self.scene {
            let aspect = self.last_key.map_or(1.5, |k| k.size[0] as f32 / k.size[1].max(1) as f32);
            self.orbit = Orbit::fit(&s.loaded.bounds, aspect);
        }
    }

    #[cfg(not(target_arch = "wasm32"))]
    fn save_image(&mut self) {
        let Some(path) = rfd::FileDialog::new().add_filter("PNG", &["png"]).set_file_name("gridrt.png").save_file()
        else {
            return;
        };
        let (Some(gpu), Some(scene), Some(b), Some(key)) = (&self.gpu, &self.scene, &self.built, self.last_key) else {
            return;
        };
        let (Some(gs), Some(s)) = (&scene.gpu, &b.gpu) else { return };
        let opts = self.render_options(key.camera, key.size);
        let result =
            gpu.renderer.render(&gpu.ctx, gs, s, &scene.loaded.bounds, &opts).map_err(|e| e.to_string()).and_then(
                |f| {
                    image::save_buffer(&path, &f.rgba, f.width, f.height, image::ExtendedColorType::Rgba8)
                        .map_err(|e| e.to_string())
                },
            );
        if let Err(e) = result {
            self.error = Some(format!("saving {}: {e}", path.display()));
        }
    }

    /// Camera input on the image: mouse and keys.
    fn camera_input(&mut self, ui: &egui::Ui, resp: &egui::Response) {
        let d = resp.drag_delta();
        let shift = ui.input(|i| i.modifiers.shift);
        let h = resp.rect.height().max(1.0);
        if resp.dragged_by(PointerButton::Primary) && !shift {
            self.orbit.rotate(d.x * 0.008, d.y * 0.008);
        } else if resp.dragged_by(PointerButton::Secondary)
            || resp.dragged_by(PointerButton::Middle)
            || (resp.dragged_by(PointerButton::Primary) && shift)
        {
            self.orbit.pan(d.x / h, d.y / h);
        }
        if resp.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.orbit.zoom((-scroll * 0.0015).exp());
            }
        }
        if resp.double_clicked() {
            self.reset_camera();
        }
        if ui.ctx().egui_wants_keyboard_input() {
            return;
        }
        let step = 0.04;
        let (l, r, u, dn, zin, zout, reset) = ui.input(|i| {
            (
                i.key_down(Key::ArrowLeft) || i.key_down(Key::A),
                i.key_down(Key::ArrowRight) || i.key_down(Key::D),
                i.key_down(Key::ArrowUp) || i.key_down(Key::W),
                i.key_down(Key::ArrowDown) || i.key_down(Key::S),
                i.key_down(Key::Plus) || i.key_down(Key::Equals) || i.key_down(Key::E),
                i.key_down(Key::Minus) || i.key_down(Key::Q),
                i.key_pressed(Key::F) || i.key_pressed(Key::Home),
            )
        });
        if l {
            self.orbit.rotate(-step, 0.0);
        }
        if r {
            self.orbit.rotate(step, 0.0);
        }
        if u {
            self.orbit.rotate(0.0, step);
        }
        if dn {
            self.orbit.rotate(0.0, -step);
        }
        if zin {
            self.orbit.zoom(0.96);
        }
        if zout {
            self.orbit.zoom(1.04);
        }
        if reset {
            self.reset_camera();
        }
        if l || r || u || dn || zin || zout {
            ui.ctx().request_repaint();
        }
    }

    /// The central image; submits a frame when the render key changed.
    /// Shares the test hook with the page (`window.gridrt`).
    #[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
    pub fn with_hook(self, hook: Hook) -> GridrtApp {
        let repaint = self.hook.lock().expect("hook lock").repaint.clone();
        hook.lock().expect("hook lock").repaint = repaint;
        GridrtApp { hook, ..self }
    }

    /// Applies the commands the page sent; captures wait until the app is idle.
    fn apply_hook_commands(&mut self, ctx: &egui::Context) {
        let commands: Vec<HookCommand> = self.hook.lock().expect("hook lock").commands.drain(..).collect();
        for c in commands {
            match c {
                HookCommand::Grid(k) => self.settings.grid.kind = k,
                HookCommand::View(v) => self.settings.view = v.name().into(),
                HookCommand::Traversal(t) => self.settings.traversal = t,
                HookCommand::Camera(cam) => match &self.scene {
                    Some(s) => self.orbit = Orbit::from_camera(&cam, &s.loaded.bounds),
                    None => self.initial_camera = Some(cam),
                },
                HookCommand::FrameSize(size) => self.frame_size = size,
                HookCommand::Open { name, bytes } => self.open(ctx, SceneSource::Bytes { name, bytes }),
                HookCommand::Capture(id) => self.captures.push_back(id),
                HookCommand::DismissError => {
                    self.error = None;
                    self.viewport.error = None;
                }
            }
        }
    }

    /// Nothing is loading, building or rendering, and the last frame shows the current settings.
    fn idle(&self) -> bool {
        self.scene_job.is_none()
            && self.build_job.is_none()
            && self.measure_job.is_none()
            && !self.viewport.busy()
            && self.frame_current
            && self.hook.lock().expect("hook lock").commands.is_empty()
    }

    /// Starts a waiting capture once idle, collects a finished one, and publishes the stats.
    fn update_hook(&mut self) {
        if self.first_frame_ms.is_none() && self.viewport.frames_done > 0 {
            #[cfg(target_arch = "wasm32")]
            let ms = web::page_ms();
            #[cfg(not(target_arch = "wasm32"))]
            let ms = Some(self.started.elapsed().as_secs_f64() * 1e3);
            self.first_frame_ms = ms;
        }
        if self.capture.is_none()
            && !self.captures.is_empty()
            && self.idle()
            && let Some(gpu) = &self.gpu
            && let Some(slot) = self.viewport.capture(gpu)
        {
            let id = self.captures.pop_back().expect("a capture");
            self.captures.clear();
            self.capture = Some((id, slot));
        }
        if let Some((id, slot)) = &self.capture {
            let done = slot.lock().expect("capture lock").take();
            match done {
                Some(Ok((width, height, rgba))) => {
                    self.hook.lock().expect("hook lock").frame = Some(CapturedFrame { id: *id, width, height, rgba });
                    self.capture = None;
                }
                Some(Err(e)) => {
                    self.error = Some(format!("reading the frame back: {e}"));
                    self.capture = None;
                }
                None => {}
            }
        }
        let built = self.built.as_ref().map(|b| &b.built);
        let last = self.viewport.last;
        let stats = HookStats {
            frames: self.viewport.frames_done,
            adapter: self.gpu.as_ref().map_or_else(String::new, |g| g.ctx.adapter_name()),
            grid: built.map_or_else(String::new, |b| b.config.kind.to_string()),
            traversal: self.settings.traversal.short_name().into(),
            view: last.map_or_else(String::new, |f| f.view.name().into()),
            scene: self.scene.as_ref().map_or_else(String::new, |s| s.loaded.name.clone()),
            triangles: self.scene.as_ref().map_or(0, |s| s.loaded.tris.len() as u64),
            mean_cells_per_ray: last.map_or(0.0, |f| f.mean_cells()),
            mean_tests_per_ray: last.map_or(0.0, |f| f.mean_tests()),
            width: last.map_or(0, |f| f.width),
            height: last.map_or(0, |f| f.height),
            frame_ms: last.map_or(0.0, |f| f.ms),
            build_ms: built.map_or(0.0, |b| b.report.times.total()),
            building: self.build_job.is_some(),
            worker_builds: self.worker_builds,
            idle: self.idle() && self.captures.is_empty() && self.capture.is_none(),
            error: [&self.error, &self.gpu_error, &self.viewport.error]
                .into_iter()
                .flatten()
                .cloned()
                .chain(self.build_error.as_ref().map(|(_, e)| e.clone()))
                .reduce(|a, b| format!("{a}; {b}")),
            first_frame_ms: self.first_frame_ms,
        };
        self.hook.lock().expect("hook lock").stats = stats;
        if (!self.captures.is_empty() || self.capture.is_some())
            && let Some(c) = &self.hook.lock().expect("hook lock").repaint
        {
            c.request_repaint();
        }
    }

    fn central(&mut self, ui: &mut egui::Ui) {
        self.frame_current = false;
        let avail = ui.available_size();
        let ppp = ui.ctx().pixels_per_point();
        let (rect, resp) = ui.allocate_exact_size(avail, Sense::click_and_drag());
        let before = self.orbit;
        self.camera_input(ui, &resp);
        if self.orbit != before {
            self.last_interaction = Some(Instant::now());
        }
        let moving = self.last_interaction.is_some_and(|t| t.elapsed().as_secs_f64() < REST_AFTER_S);
        if !moving {
            self.interactive_factor = 1.0;
        } else {
            // One adjustment per finished frame, towards INTERACTIVE_FRAME_MS (pixels ~ factor²).
            if let Some(f) = self.viewport.last
                && self.viewport.frames_done != self.factor_frame
            {
                self.factor_frame = self.viewport.frames_done;
                self.interactive_factor =
                    (self.interactive_factor * (INTERACTIVE_FRAME_MS / f.ms).sqrt() as f32).clamp(0.2, 1.0);
            }
            ui.ctx().request_repaint_after(std::time::Duration::from_secs_f64(REST_AFTER_S));
        }
        let scale = self.settings.render_scale.clamp(0.05, 1.0) * self.interactive_factor;
        let size = self.frame_size.unwrap_or([
            ((avail.x * ppp * scale).round() as u32).clamp(1, gridrt_gpu::render::MAX_IMAGE_SIDE),
            ((avail.y * ppp * scale).round() as u32).clamp(1, gridrt_gpu::render::MAX_IMAGE_SIDE),
        ]);
        if let Some(tex) = self.viewport.texture() {
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            // A fixed frame size keeps its aspect, letterboxed in the view.
            let shown = match self.frame_size {
                Some([w, h]) => {
                    let k = (rect.width() / w as f32).min(rect.height() / h as f32);
                    egui::Rect::from_center_size(rect.center(), Vec2::new(w as f32 * k, h as f32 * k))
                }
                None => rect,
            };
            ui.painter().image(tex, shown, uv, egui::Color32::WHITE);
        }
        if let Some(job) = &self.scene_job {
            ui.put(
                egui::Rect::from_center_size(rect.center(), Vec2::new(320.0, 40.0)),
                egui::Label::new(format!("{}… {:.1} s", job.what, job.elapsed_s())),
            );
        }
        let Some(gpu) = &self.gpu else { return };
        let (Some(scene), Some(b)) = (&self.scene, &self.built) else { return };
        let (Some(gs), Some(s)) = (&scene.gpu, &b.gpu) else { return };
        if b.built.scene_generation != scene.generation {
            return;
        }
        let key = RenderKey {
            camera: self.orbit.camera(),
            view: self.view(),
            traversal: self.settings.traversal,
            mailbox: self.settings.mailbox,
            heat_max: self.settings.heat_max,
            size,
            structure: b.id,
        };
        // Smoke mode renders its N frames back to back.
        let smoke_wants_frame =
            self.smoke.as_ref().is_some_and(|sm| self.viewport.frames_done < sm.frames as u64) && !self.viewport.busy();
        if Some(key) != self.last_key || smoke_wants_frame {
            self.viewport.start(&self.render_options(key.camera, size));
            self.last_key = Some(key);
        }
        if let Err(e) =
            self.viewport.step(gpu, gs, s, &scene.loaded.bounds).and_then(|done| gpu.ctx.check_device().map(|()| done))
        {
            self.viewport.cancel();
            self.viewport.error = Some(e.to_string());
        }
        self.frame_current = true;
        if self.viewport.busy() {
            ui.ctx().request_repaint();
        }
    }

    /// Smoke mode: once enough frames are done, screenshot the window, save it and close.
    fn smoke_step(&mut self, ctx: &egui::Context) {
        let frames_done = self.viewport.frames_done;
        let Some(s) = &mut self.smoke else { return };
        ctx.request_repaint();
        if s.started.elapsed().as_secs_f64() > SMOKE_TIMEOUT_S {
            let why = format!("smoke run timed out after {SMOKE_TIMEOUT_S} s ({frames_done} frames done)");
            self.fail_smoke(ctx, why);
            return;
        }
        let measuring = self.measure_at_start || self.measurement.running() || self.measure_job.is_some();
        if !s.requested && frames_done >= s.frames as u64 && !self.viewport.busy() && !measuring {
            s.requested = true;
            let shot = s.shot.clone();
            ctx.request_screenshot(move |img| *shot.lock().expect("screenshot") = Some(img));
            return;
        }
        let Some(img) = s.shot.lock().expect("screenshot").take() else { return };
        let rgba: Vec<u8> = img.pixels.iter().flat_map(|c| c.to_array()).collect();
        let [w, h] = img.size;
        let result = image::save_buffer(&s.path, &rgba, w as u32, h as u32, image::ExtendedColorType::Rgba8)
            .map(|()| {
                let f = self.viewport.last;
                format!(
                    "saved {}x{} screenshot to {} after {frames_done} frames{}{}",
                    w,
                    h,
                    s.path.display(),
                    f.map_or(String::new(), |f| format!(
                        " (last frame {}x{}: {:.1} ms, {:.2} cells/ray, {:.2} tests/ray)",
                        f.width,
                        f.height,
                        f.ms,
                        f.mean_cells(),
                        f.mean_tests()
                    )),
                    match self.measurement.results.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
                        Some(best) => format!(
                            "; cost model: {} resolutions timed, fastest m = {:.1} ({:.1} ms)",
                            self.measurement.results.len(),
                            best.0,
                            best.1
                        ),
                        None => String::new(),
                    }
                )
            })
            .map_err(|e| format!("writing {}: {e}", s.path.display()));
        *s.status.lock().expect("smoke status") = Some(result);
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }

    /// A .glb/.gltf dropped on the window opens (the first one, if several).
    #[cfg(not(target_arch = "wasm32"))]
    fn dropped_files(&mut self, ctx: &egui::Context) {
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        if let Some(f) = dropped.into_iter().next() {
            self.open(ctx, SceneSource::Path(f.path().to_path_buf()));
        }
    }

    /// In the browser a dropped file's bytes arrive asynchronously; the load starts when they
    /// are here.
    #[cfg(target_arch = "wasm32")]
    fn dropped_files(&mut self, ctx: &egui::Context) {
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        if let Some(f) = dropped.into_iter().next() {
            let (tx, rx) = std::sync::mpsc::channel();
            let name = f.path().to_string_lossy().into_owned();
            let ui = ctx.clone();
            wasm_bindgen_futures::spawn_local(async move {
                let _ = tx.send(f.bytes_async().await.map(|b| (name, b)));
                ui.request_repaint();
            });
            self.dropped = Some(rx);
        }
        if let Some(rx) = &self.dropped
            && let Ok(r) = rx.try_recv()
        {
            self.dropped = None;
            match r {
                Ok((name, bytes)) => self.open(ctx, SceneSource::Bytes { name, bytes: bytes.into() }),
                Err(e) => self.error = Some(format!("reading the dropped file: {e}")),
            }
        }
    }
}

impl eframe::App for GridrtApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.apply_hook_commands(&ctx);
        self.poll_jobs(&ctx);
        self.dropped_files(&ctx);
        if self.scene_job.is_some() || self.build_job.is_some() || self.measure_job.is_some() {
            ctx.request_repaint_after(std::time::Duration::from_millis(100));
        }
        egui::Panel::top("menu").show(ui, |ui| self.menu(ui));
        egui::Panel::left("controls").resizable(true).default_size(290.0).size_range(200.0..=480.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                let built = self.built.as_ref().map(|b| &b.built);
                panels::controls(ui, &mut self.settings, built);
            });
        });
        egui::Panel::right("stats").resizable(true).default_size(270.0).size_range(180.0..=480.0).show(ui, |ui| {
            ui.heading("Stats");
            let adapter = self.gpu.as_ref().map_or("none".to_string(), |g| g.ctx.adapter_name());
            let scene = self.scene.as_ref().map(|s| &s.loaded);
            let building = self
                .build_job
                .as_ref()
                .map(|j| (j.what.clone(), j.elapsed_s()))
                .or_else(|| self.scene_job.as_ref().map(|j| (j.what.clone(), j.elapsed_s())));
            panels::stats(
                ui,
                &adapter,
                scene,
                self.built.as_ref().map(|b| &b.built),
                building,
                self.viewport.last.as_ref(),
            );
            for e in [&self.gpu_error, &self.viewport.error].into_iter().flatten() {
                ui.colored_label(ui.visuals().error_fg_color, e);
            }
            if let Some((_, e)) = &self.build_error {
                ui.colored_label(ui.visuals().error_fg_color, e);
            }
            if let Some(e) = self.error.clone() {
                ui.separator();
                ui.colored_label(ui.visuals().error_fg_color, e);
                if ui.button("dismiss").clicked() {
                    self.error = None;
                }
            }
        });
        egui::CentralPanel::default().show(ui, |ui| self.central(ui));

        let mut open = self.settings.show_cost_plot;
        egui::Window::new("Cost model").open(&mut open).default_pos([330.0, 40.0]).default_size([520.0, 420.0]).show(
            &ctx,
            |ui| {
                let choice = self.built.as_ref().and_then(|b| b.built.report.resolution_choice.as_ref());
                let view = cost_plot::CostView {
                    curve: choice.map(|c| c.curve.as_slice()),
                    chosen: choice.map(|c| c.resolution),
                    policy: choice.map_or("kind default".into(), |c| format!("{:?}", c.policy)),
                    measurement: &self.measurement,
                };
                if cost_plot::ui(ui, &view)
                    && let Some(c) = choice
                {
                    self.measurement = cost_plot::Measurement {
                        pending: c.curve.iter().map(|s| s.resolution).collect(),
                        results: Vec::new(),
                        total: c.curve.len(),
                    };
                }
            },
        );
        self.settings.show_cost_plot = open;
        let mut open = self.settings.show_explainer;
        egui::Window::new("Traversal explainer")
            .open(&mut open)
            .default_pos([360.0, 110.0])
            .default_size([560.0, 520.0])
            .show(&ctx, |ui| {
                explainer::ui(ui, &mut self.settings.explainer);
            });
        self.settings.show_explainer = open;
        self.smoke_step(&ctx);
        self.update_hook();
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        if self.smoke.is_none() {
            eframe::set_value(storage, settings::STORAGE_KEY, &self.settings);
        }
    }
}

/// wgpu setup shared by the native and web mains: the device asks for the limits gridrt's
/// kernels need (within what the adapter offers), plus a texture size for large windows.
pub fn wgpu_options() -> eframe::egui_wgpu::WgpuConfiguration {
    use eframe::egui_wgpu::{WgpuConfiguration, WgpuSetup, WgpuSetupCreateNew};
    let mut setup = WgpuSetupCreateNew::without_display_handle();
    setup.device_descriptor = Arc::new(|adapter| {
        let offered = adapter.limits();
        let mut limits = gridrt_gpu::context::required_limits(&offered);
        limits.max_texture_dimension_2d =
            offered.max_texture_dimension_2d.min(8192).max(limits.max_texture_dimension_2d);
        wgpu::DeviceDescriptor { label: Some("gridrt app device"), required_limits: limits, ..Default::default() }
    });
    // WGPU_ADAPTER_NAME picks the adapter by name, as for the command line.
    #[cfg(not(target_arch = "wasm32"))]
    if let Ok(wanted) = std::env::var("WGPU_ADAPTER_NAME") {
        let wanted = wanted.to_lowercase();
        setup.native_adapter_selector = Some(Arc::new(move |adapters, _surface| {
            adapters.iter().find(|a| a.get_info().name.to_lowercase().contains(&wanted)).cloned().ok_or_else(|| {
                let found: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
                format!("WGPU_ADAPTER_NAME matches no adapter; found {found:?}")
            })
        }));
    }
    WgpuConfiguration { wgpu_setup: WgpuSetup::CreateNew(setup), ..Default::default() }
}

/// Runs the desktop app (blocking until its window closes).
#[cfg(not(target_arch = "wasm32"))]
pub fn run_native(args: AppArgs) -> anyhow::Result<()> {
    let status: SmokeStatus = Default::default();
    let smoke = args.screenshot.is_some();
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size([args.window_size.0 as f32, args.window_size.1 as f32])
            .with_title("gridrt"),
        wgpu_options: wgpu_options(),
        persist_window: !smoke,
        ..Default::default()
    };
    let st = status.clone();
    eframe::run_native(
        "gridrt",
        options,
        Box::new(move |cc| Ok(Box::new(GridrtApp::new(cc, args, st)) as Box<dyn eframe::App>)),
    )
    .map_err(|e| anyhow::anyhow!("the app failed: {e}"))?;
    if smoke {
        match status.lock().expect("smoke status").take() {
            Some(Ok(msg)) => println!("{msg}"),
            Some(Err(e)) => anyhow::bail!("smoke run failed: {e}"),
            None => anyhow::bail!("the window closed before the screenshot was taken"),
        }
    }
    Ok(())
}

/// Starts the app in a browser, on the canvas with id `gridrt_canvas` (web/index.html). A
/// failure (no WebGPU, no adapter) replaces the page's loading text with the reason.
#[cfg(target_arch = "wasm32")]
pub fn start_web() {
    use eframe::wasm_bindgen::JsCast as _;
    eframe::WebLogger::init(log::LevelFilter::Info).ok();
    let options = eframe::WebOptions { wgpu_options: wgpu_options(), ..Default::default() };
    wasm_bindgen_futures::spawn_local(async move {
        let document = eframe::web_sys::window().and_then(|w| w.document()).expect("a browser document");
        let canvas = document
            .get_element_by_id("gridrt_canvas")
            .expect("web/index.html has a canvas with id gridrt_canvas")
            .dyn_into::<eframe::web_sys::HtmlCanvasElement>()
            .expect("gridrt_canvas is a canvas");
        let status: SmokeStatus = Default::default();
        let hook: Hook = Default::default();
        let runner = eframe::WebRunner::new();
        web::install(hook.clone(), runner.clone());
        let result = runner
            .start(
                canvas,
                options,
                Box::new(move |cc| {
                    let app = GridrtApp::new(cc, AppArgs::default(), status).with_hook(hook);
                    Ok(Box::new(app) as Box<dyn eframe::App>)
                }),
            )
            .await;
        if let Some(el) = document.get_element_by_id("loading_text") {
            match result {
                Ok(()) => el.remove(),
                Err(e) => el.set_inner_html(&format!("<p>gridrt could not start: {e:?}</p>")),
            }
        }
    });
}
