//! Unattended runs: `--screenshot out.png --frames N` renders N frames, saves the window and
//! exits; and the test hook (`window.gridrt` in the browser) that drives the app and reads its
//! stats and frames.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use eframe::egui;
use web_time::Instant;

use super::built::BuiltOn;
use super::errors::ErrorKind;
use super::hook::{CapturedFrame, Hook, HookCommand, HookStats};
use super::jobs::SceneSource;
use super::orbit::Orbit;
use super::{GridrtApp, SmokeStatus};
use crate::cli::CameraArg;

/// `--screenshot out.png --frames N`: render N frames, save the window, exit.
#[derive(Debug)]
pub(super) struct Smoke {
    pub(super) path: PathBuf,
    pub(super) frames: u32,
    pub(super) requested: bool,
    pub(super) shot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
    pub(super) status: SmokeStatus,
    pub(super) started: Instant,
}

/// Seconds a smoke run may take before it gives up.
pub(super) const SMOKE_TIMEOUT_S: f64 = 600.0;

impl GridrtApp {
    pub(super) fn fail_smoke(&mut self, ctx: &egui::Context, why: String) {
        if let Some(s) = &self.smoke {
            *s.status.lock().expect("smoke status") = Some(Err(why));
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
    }

    /// Smoke mode: once enough frames are done, screenshot the window, save it and close.
    pub(super) fn smoke_step(&mut self, ctx: &egui::Context) {
        // Every UI pass calls this: outside smoke mode it must cost nothing.
        if self.smoke.is_none() {
            return;
        }
        let frames_done = self.viewport.frames_done;
        let animation = self.animation_stats();
        let on_gpu = self.built.as_ref().is_some_and(|b| b.built.built_on == BuiltOn::Gpu);
        let off_gpu = self.off_gpu().map_or(String::new(), |why| format!("; {why}"));
        let adapter = self.gpu.as_ref().map_or("none".into(), |g| g.ctx.adapter_name());
        let trace_on = self.settings.trace_on.name();
        let Some(s) = &mut self.smoke else { return };
        // Polled, not a repaint loop: finished frames and jobs wake the UI themselves, and a
        // loop would take the cores from the frames being timed.
        ctx.request_repaint_after(std::time::Duration::from_millis(super::FRAME_POLL_MS));
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
                    "saved {}x{} screenshot to {} after {frames_done} frames{}{}{}{}{}; trace on {trace_on}; \
                     adapter {adapter}",
                    w,
                    h,
                    s.path.display(),
                    f.map_or(String::new(), |f| format!(
                        " (last frame {}x{}: {:.1} ms on the {}, {:.2} cells/ray, {:.2} tests/ray)",
                        f.width,
                        f.height,
                        f.ms,
                        if f.on_cpu { "CPU" } else { "GPU" },
                        f.mean_cells(),
                        f.mean_tests()
                    )),
                    off_gpu,
                    if on_gpu { "; structure built on the GPU" } else { "" },
                    match animation {
                        Some(a) => format!(
                            "; animation: {} frames shown, {} fps (pose {:.1}, build {:.1}, upload {:.1}, trace {:.1} ms)",
                            a.frames_shown,
                            a.fps.map_or("-".into(), |f| format!("{f:.2}")),
                            a.pose_ms,
                            a.build_ms,
                            a.upload_ms,
                            a.trace_ms
                        ),
                        None => String::new(),
                    },
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

    /// Shares the test hook with the page (`window.gridrt`).
    #[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
    pub fn with_hook(self, hook: Hook) -> GridrtApp {
        let repaint = self.hook.lock().expect("hook lock").repaint.clone();
        hook.lock().expect("hook lock").repaint = repaint;
        GridrtApp { hook, ..self }
    }

    /// Applies the commands the page sent; captures wait until the app is idle.
    pub(super) fn apply_hook_commands(&mut self, ctx: &egui::Context) {
        let commands: Vec<HookCommand> = self.hook.lock().expect("hook lock").commands.drain(..).collect();
        for c in commands {
            match c {
                HookCommand::Grid(k) => self.settings.grid.kind = k,
                HookCommand::View(v) => self.settings.view = v,
                HookCommand::Traversal(t) => self.settings.traversal = t,
                HookCommand::Camera(cam) => match &self.scene {
                    Some(s) => self.orbit = Orbit::from_camera(&cam, &s.loaded.bounds),
                    None => self.initial_camera = Some(CameraArg::At(cam)),
                },
                HookCommand::FrameSize(size) => self.frame_size = size,
                HookCommand::Open { name, bytes } => self.open(ctx, SceneSource::Bytes { name, bytes }),
                HookCommand::Capture(id) => self.captures.push_back(id),
                HookCommand::DismissError => self.errors.clear(|k| matches!(k, ErrorKind::Other | ErrorKind::Render)),
                HookCommand::Playing(on) => {
                    if let (Some(t), Some(s)) = (&mut self.timeline, &self.scene)
                        && t.playing != on
                    {
                        t.toggle(&s.loaded.clips[t.clip]);
                    }
                }
                HookCommand::GpuBuild(on) => self.settings.gpu_build = on,
                HookCommand::Packets(on) => self.settings.packets = on,
                HookCommand::Seek(seconds) => {
                    if let (Some(t), Some(s)) = (&mut self.timeline, &self.scene) {
                        t.seek(&s.loaded.clips[t.clip], seconds);
                    }
                }
            }
        }
    }

    /// The timeline as the hook and the smoke run report it.
    pub(super) fn animation_stats(&self) -> Option<super::hook::AnimationStats> {
        let t = self.timeline.as_ref()?;
        let m = t.mean(30).unwrap_or(super::timeline::FrameTimes::zero());
        Some(super::hook::AnimationStats {
            clip: t.clip,
            seconds: t.seconds,
            shown_seconds: self.built.as_ref().and_then(|b| b.built.pose.as_ref()).map(|p| p.time.seconds),
            playing: t.playing,
            frames_shown: t.frames_shown,
            fps: t.fps(),
            pose_ms: m.pose_ms,
            build_ms: m.build_ms,
            upload_ms: m.upload_ms,
            trace_ms: m.trace_ms,
        })
    }

    /// Nothing is loading, building or rendering, and the last frame shows the current settings.
    pub(super) fn idle(&self) -> bool {
        self.scene_job.is_none()
            && self.build_job.is_none()
            && self.measure_job.is_none()
            && !self.viewport.busy()
            && self.frame_current
            && self.hook.lock().expect("hook lock").commands.is_empty()
    }

    /// Starts a waiting capture once idle, collects a finished one, and publishes the stats.
    pub(super) fn update_hook(&mut self) {
        if self.first_frame_ms.is_none() && self.viewport.frames_done > 0 {
            #[cfg(target_arch = "wasm32")]
            let ms = super::web::page_ms();
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
                    self.errors.report(ErrorKind::Other, format!("reading the frame back: {e}"));
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
            packets: self.settings.packets,
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
            gpu_built: built.is_some_and(|b| b.built_on == BuiltOn::Gpu),
            idle: self.idle() && self.captures.is_empty() && self.capture.is_none(),
            error: self.errors.joined(),
            first_frame_ms: self.first_frame_ms,
            animation: self.animation_stats(),
        };
        self.hook.lock().expect("hook lock").stats = stats;
        if (!self.captures.is_empty() || self.capture.is_some())
            && let Some(c) = &self.hook.lock().expect("hook lock").repaint
        {
            c.request_repaint();
        }
    }
}
