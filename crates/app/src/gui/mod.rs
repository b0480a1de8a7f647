//! The desktop (and browser) app: eframe on wgpu, sharing eframe's device with `gridrt-gpu`.
//!
//! Data flows one way, as in the library: a scene (loaded off the UI thread) → a structure
//! (built off the UI thread) → GPU buffers → a rendered texture and its stats. The UI edits
//! [`Settings`]; when the wanted structure differs from the built one a rebuild starts (the
//! previous structure stays on screen meanwhile), and when anything the image depends on
//! changes a frame is rendered.

pub mod built;
pub mod cost_plot;
pub mod errors;
pub mod explainer;
pub mod hook;
mod input;
pub mod jobs;
mod lifecycle;
mod measure;
pub mod orbit;
pub mod panels;
pub mod settings;
mod smoke;
pub mod timeline;
pub mod viewport;
#[cfg(target_arch = "wasm32")]
pub mod web;

use std::sync::{Arc, Mutex};

use eframe::egui::{self, Sense, Vec2};
use gridrt_gpu::{FrameSource, RenderOptions, View};
use gridrt_scene::Camera;
use web_time::Instant;

use crate::cli::{AppArgs, CameraArg};
use built::Built;
use errors::{ErrorKind, Errors};
use hook::Hook;
use jobs::{Job, LoadedScene, SceneSource};
use lifecycle::{BuiltState, SceneState};
use orbit::Orbit;
use settings::Settings;
use smoke::Smoke;
use timeline::{FrameTimes, Timeline};
use viewport::{Gpu, Viewport};

/// How a smoke run (`--screenshot`) ended: `Ok(message)` or `Err(reason)`.
pub type SmokeStatus = Arc<Mutex<Option<Result<String, String>>>>;

/// Everything a frame depends on: a new frame is rendered when this changes.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RenderKey {
    camera: Camera,
    view: View,
    traversal: gridrt_grid::Traversal,
    mailbox: bool,
    packets: bool,
    heat_max: f32,
    size: [u32; 2],
    structure: u64,
    cpu_trace: bool,
}

pub struct GridrtApp {
    settings: Settings,
    smoke: Option<Smoke>,
    gpu: Option<Gpu>,
    scene: Option<SceneState>,
    scene_generation: u64,
    scene_job: Option<Job<Result<LoadedScene, String>>>,
    build_job: Option<Job<Result<Built, String>>>,
    built: Option<BuiltState>,
    built_counter: u64,
    orbit: Orbit,
    viewport: Viewport,
    last_key: Option<RenderKey>,
    /// Every error shown (load, build, GPU, render); the previous scene and structure stay.
    errors: Errors,
    measurement: cost_plot::Measurement,
    measure_job: Option<Job<Result<Built, String>>>,
    /// `--camera`: used for the first scene instead of framing its bounds (a framed or interior
    /// view once its first structure is built: they probe it).
    initial_camera: Option<CameraArg>,
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
    /// The animated scene's timeline (`None`: the scene has no clips).
    timeline: Option<Timeline>,
    /// How the first animated scene starts (`--animation`, `--time`, `--paused`).
    animation_start: AnimationStart,
    /// An animation frame built while the previous one was still rendering.
    ready: Option<built::Built>,
    /// The build job running poses the scene.
    posing: bool,
    /// The structure whose frame the timeline recorded last.
    recorded: u64,
    /// `--animation` named no clip of the scene (a smoke run fails with it).
    start_error: Option<String>,
}

/// How an animated scene starts playing.
#[derive(Clone, Debug, Default)]
struct AnimationStart {
    clip: Option<String>,
    seconds: Option<f64>,
    paused: bool,
}

/// While the camera moves, frames slower than this are rendered at a lower resolution; the
/// full resolution follows when the camera rests.
const INTERACTIVE_FRAME_MS: f64 = 60.0;
/// How long after the last camera move the view counts as resting.
const REST_AFTER_S: f64 = 0.3;

/// While a frame is being traced the native UI sleeps: the CPU trace's job, the GPU tile
/// waiter and the totals' readback wake it when their work is done (the interval is only a
/// fallback). Repainting the window meanwhile took cores from the tracer on a software adapter
/// (README, "Dynamic scenes in the app"). In a browser nothing wakes the UI when the GPU is
/// done, so it polls every frame.
fn wait_for_frame(ctx: &egui::Context) {
    #[cfg(not(target_arch = "wasm32"))]
    ctx.request_repaint_after(std::time::Duration::from_millis(FRAME_POLL_MS));
    #[cfg(target_arch = "wasm32")]
    ctx.request_repaint();
}

/// See [`wait_for_frame`] (and smoke mode, which polls as seldom).
const FRAME_POLL_MS: u64 = 250;

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
        if let Some(v) = args.view {
            settings.view = v;
        }
        if let Some(t) = args.traversal {
            settings.traversal = t;
        }
        if let Some(p) = args.packets {
            settings.packets = p == crate::cli::Switch::On;
        }
        if smoke.is_some() {
            settings.render_scale = 1.0;
        }
        if let Some(r) = args.render_scale {
            settings.render_scale = r.clamp(0.05, 1.0);
        }
        if args.gpu_build {
            settings.gpu_build = true;
        }
        if args.exact {
            settings.grid.build.insert = gridrt_grid::InsertMode::Exact;
        }
        if let Some(t) = args.trace_on.or(args.cpu_trace.then_some(settings::TraceOn::Cpu)) {
            settings.trace_on = t;
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
        let mut errors = Errors::default();
        let gpu = match cc.wgpu_render_state.as_ref() {
            Some(rs) => match Gpu::new(rs, &cc.egui_ctx) {
                Ok(g) => Some(g),
                Err(e) => {
                    errors.report(ErrorKind::Gpu, format!("GPU setup failed: {e}"));
                    None
                }
            },
            None => {
                errors.report(ErrorKind::Gpu, "eframe started without a wgpu device");
                None
            }
        };
        let mut app = GridrtApp {
            settings,
            smoke,
            gpu,
            scene: None,
            scene_generation: 0,
            scene_job: None,
            build_job: None,
            built: None,
            built_counter: 0,
            orbit: Orbit::fit(&gridrt_scene::Aabb::from_points(&[glam::Vec3::ZERO, glam::Vec3::ONE]), 1.5),
            viewport: Viewport::default(),
            last_key: None,
            errors,
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
            timeline: None,
            animation_start: AnimationStart { clip: args.animation.clone(), seconds: args.time, paused: args.paused },
            ready: None,
            posing: false,
            recorded: 0,
            start_error: None,
        };
        app.hook.lock().expect("hook lock").repaint = Some(cc.egui_ctx.clone());
        let source = args.scene.map_or(SceneSource::Default, SceneSource::Path);
        app.open(&cc.egui_ctx, source);
        app
    }

    fn render_options(&self, camera: Camera, size: [u32; 2]) -> RenderOptions {
        RenderOptions {
            width: size[0],
            height: size[1],
            camera,
            view: self.settings.view,
            traversal: self.settings.traversal,
            mailbox: self.settings.mailbox,
            heat_max: self.settings.heat_max,
            packets: self.settings.packets,
        }
    }

    /// The central image; submits a frame when the render key changed.
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
        let cpu_trace = self.cpu_traces();
        let Some(gpu) = &self.gpu else { return };
        let (Some(scene), Some(b)) = (&self.scene, &self.built) else { return };
        // The triangles and structure on the device (none when it cannot hold them: the CPU
        // traces them then).
        let on_device = b.posed_gpu.as_ref().or(scene.gpu.as_ref()).zip(b.gpu.as_ref());
        if b.built.scene_generation != scene.generation || (on_device.is_none() && !cpu_trace) {
            return;
        }
        let key = RenderKey {
            camera: self.orbit.camera(),
            view: self.settings.view,
            traversal: self.settings.traversal,
            mailbox: self.settings.mailbox,
            packets: self.settings.packets,
            heat_max: self.settings.heat_max,
            size,
            structure: b.id,
            cpu_trace,
        };
        // Smoke mode renders its N frames back to back.
        let smoke_wants_frame =
            self.smoke.as_ref().is_some_and(|sm| self.viewport.frames_done < sm.frames as u64) && !self.viewport.busy();
        if Some(key) != self.last_key || smoke_wants_frame {
            let opts = self.render_options(key.camera, size);
            #[cfg(not(target_arch = "wasm32"))]
            if key.cpu_trace {
                let tris = b.built.pose.as_ref().map_or_else(|| scene.loaded.tris.clone(), |p| p.tris.clone());
                let bounds = scene.loaded.bounds;
                self.viewport.start_cpu(viewport::CpuRequest { opts, grid: b.built.grid.clone(), tris, bounds });
            } else {
                self.viewport.start(&opts);
            }
            #[cfg(target_arch = "wasm32")]
            self.viewport.start(&opts);
            self.last_key = Some(key);
        }
        let source = on_device.map(|(gs, s)| FrameSource { scene: gs, structure: s, bounds: &scene.loaded.bounds });
        match self.viewport.step(gpu, source.as_ref()).and_then(|done| gpu.ctx.check_device().map(|()| done)) {
            // A finished frame ends an earlier render error; the next frame (of an animation,
            // of smoke mode) starts in the next pass.
            Ok(true) => {
                ui.ctx().request_repaint();
                self.errors.clear(|k| *k == ErrorKind::Render);
                if let (Some(tl), Some(p), Some(f)) = (&mut self.timeline, &b.built.pose, &self.viewport.last)
                    && self.recorded != b.id
                {
                    self.recorded = b.id;
                    let times = FrameTimes {
                        frame: 0,
                        seconds: p.time.seconds,
                        pose_ms: p.pose_ms,
                        build_ms: b.built.report.times.total(),
                        upload_ms: b.upload_ms,
                        trace_ms: f.ms,
                    };
                    tl.record(times, Instant::now());
                }
            }
            Ok(false) => {}
            Err(e) => {
                self.viewport.cancel();
                self.errors.report(ErrorKind::Render, e.to_string());
            }
        }
        self.frame_current = true;
        if self.viewport.busy() {
            wait_for_frame(ui.ctx());
        }
    }
}

impl eframe::App for GridrtApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.apply_hook_commands(&ctx);
        if let (Some(tl), Some(scene)) = (&mut self.timeline, &self.scene)
            && let Some(clip) = scene.loaded.clips.get(tl.clip)
        {
            tl.tick(clip, Instant::now());
            if tl.playing {
                ctx.request_repaint_after(std::time::Duration::from_millis(100));
            }
        }
        self.poll_jobs(&ctx);
        self.dropped_files(&ctx);
        if self.scene_job.is_some() || self.build_job.is_some() || self.measure_job.is_some() {
            ctx.request_repaint_after(std::time::Duration::from_millis(100));
        }
        egui::Panel::top("menu").show(ui, |ui| self.menu(ui));
        egui::Panel::left("controls").resizable(true).default_size(290.0).size_range(200.0..=480.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                let built = self.built.as_ref().map(|b| &b.built);
                let off_gpu = self.off_gpu().map(str::to_owned);
                let software = self.software_adapter();
                panels::controls(ui, &mut self.settings, built, off_gpu.as_deref(), software);
            });
        });
        egui::Panel::right("stats").resizable(true).default_size(270.0).size_range(180.0..=480.0).show(ui, |ui| {
            ui.heading("Stats");
            let adapter = self.gpu.as_ref().map_or("none".to_string(), |g| g.ctx.adapter_name());
            let scene = self.scene.as_ref().map(|s| &s.loaded);
            // A playing animation's rebuilds show in the timeline, not as a spinner.
            let building = self
                .build_job
                .as_ref()
                .filter(|_| !self.posing)
                .map(|j| (j.what.clone(), j.elapsed_s()))
                .or_else(|| self.scene_job.as_ref().map(|j| (j.what.clone(), j.elapsed_s())));
            panels::stats(
                ui,
                &adapter,
                scene,
                self.built.as_ref().map(|b| &b.built),
                building,
                self.viewport.last.as_ref(),
                self.off_gpu(),
            );
            let mut dismissable = false;
            for (kind, e) in self.errors.iter() {
                ui.colored_label(ui.visuals().error_fg_color, e);
                dismissable |= *kind == ErrorKind::Other;
            }
            if dismissable && ui.button("dismiss").clicked() {
                self.errors.clear(|k| *k == ErrorKind::Other);
            }
        });
        if let (Some(tl), Some(scene)) = (&mut self.timeline, &self.scene) {
            egui::Panel::bottom("timeline").resizable(true).default_size(170.0).size_range(60.0..=480.0).show(
                ui,
                |ui| {
                    timeline::ui(ui, tl, &scene.loaded.clips);
                },
            );
        }
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

/// wgpu setup shared by the native and web mains: the device asks for the features and limits
/// gridrt's kernels need (within what the adapter offers), plus a texture size for large windows;
/// `max_buffer` caps its storage-buffer binding size (`--max-gpu-buffer`).
pub fn wgpu_options(max_buffer: Option<u64>) -> eframe::egui_wgpu::WgpuConfiguration {
    use eframe::egui_wgpu::{WgpuConfiguration, WgpuSetup, WgpuSetupCreateNew};
    let mut setup = WgpuSetupCreateNew::without_display_handle();
    setup.device_descriptor = Arc::new(move |adapter| {
        let offered = adapter.limits();
        let mut limits = gridrt_gpu::context::required_limits(&offered);
        limits.max_texture_dimension_2d =
            offered.max_texture_dimension_2d.min(8192).max(limits.max_texture_dimension_2d);
        if let Some(cap) = max_buffer {
            limits.max_storage_buffer_binding_size = limits.max_storage_buffer_binding_size.min(cap);
        }
        wgpu::DeviceDescriptor {
            label: Some("gridrt app device"),
            required_features: gridrt_gpu::context::required_features(adapter.features()),
            required_limits: limits,
            ..Default::default()
        }
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

/// What to do when the app cannot open a window because there is no display (a server, a
/// container, a CI job): empty when a display is set.
#[cfg(not(target_arch = "wasm32"))]
fn no_display_hint() -> &'static str {
    let set = |v: &str| std::env::var_os(v).is_some_and(|s| !s.is_empty());
    if cfg!(target_os = "linux") && !set("DISPLAY") && !set("WAYLAND_DISPLAY") && !set("WAYLAND_SOCKET") {
        " (no display here: run the app under Xvfb, e.g. `xvfb-run -a gridrt SCENE`, or use the \
         command line, e.g. `gridrt render SCENE -o out.png`; `gridrt --help` lists the commands)"
    } else {
        ""
    }
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
        wgpu_options: wgpu_options(args.max_gpu_buffer),
        persist_window: !smoke,
        ..Default::default()
    };
    let st = status.clone();
    eframe::run_native(
        "gridrt",
        options,
        Box::new(move |cc| Ok(Box::new(GridrtApp::new(cc, args, st)) as Box<dyn eframe::App>)),
    )
    .map_err(|e| anyhow::anyhow!("the app failed: {e}{}", no_display_hint()))?;
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
    let options = eframe::WebOptions { wgpu_options: wgpu_options(None), ..Default::default() };
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
