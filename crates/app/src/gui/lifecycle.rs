//! The app's document lifecycle: a scene is loaded off the UI thread and uploaded, the
//! structure the settings ask for is built off the UI thread and uploaded; a failure keeps the
//! previous scene or structure on screen and is reported. An animated scene is posed at the
//! timeline's time and rebuilt with every pose; a finished frame waits until the frame on
//! screen is complete, so every pose built is shown. Natively, a scene or structure larger than
//! the device's buffer limits stays on the CPU: its frames are traced there ([`GridrtApp::off_gpu`]).

use eframe::egui;
use gridrt_gpu::GpuError;
use gridrt_gpu::upload::{GpuScene, GpuStructure};
use gridrt_grid::GridConfig;
use gridrt_grid::cell_plane::CellPlanes;

use super::GridrtApp;
use super::errors::ErrorKind;
use super::jobs::{self, Job, LoadedScene, SceneSource};
use super::orbit::Orbit;
use super::timeline::Timeline;
use crate::cli::CameraArg;
use crate::format::human_bytes;
use crate::gui::built::{Built, BuiltOn};

#[derive(Debug)]
pub(super) struct SceneState {
    pub(super) loaded: LoadedScene,
    pub(super) gpu: Option<GpuScene>,
    /// Natively, why the device does not hold the scene (a buffer beyond its limits): its
    /// structures stay on the CPU, which traces its frames.
    pub(super) off_gpu: Option<String>,
    pub(super) generation: u64,
}

#[derive(Debug)]
pub(super) struct BuiltState {
    pub(super) built: Built,
    pub(super) gpu: Option<GpuStructure>,
    /// The posed triangles on the GPU (`None`: the scene's own, the rest pose).
    pub(super) posed_gpu: Option<GpuScene>,
    /// Posed triangles and structure copied to the GPU, milliseconds.
    pub(super) upload_ms: f64,
    /// Natively, why the device does not hold this structure or its pose: the CPU traces it.
    pub(super) off_gpu: Option<String>,
    /// Changes with every new structure (part of the render key).
    pub(super) id: u64,
}

impl GridrtApp {
    /// Starts loading a scene; the current one stays until the new one is ready.
    pub(super) fn open(&mut self, ctx: &egui::Context, source: SceneSource) {
        let label = source.label();
        self.scene_job = Some(Job::spawn(format!("loading {label}"), ctx, move || jobs::load_scene(&source)));
    }

    /// Collects finished jobs and starts the builds the settings ask for.
    pub(super) fn poll_jobs(&mut self, ctx: &egui::Context) {
        if let Some(job) = &mut self.scene_job
            && let Some(r) = job.poll()
        {
            self.scene_job = None;
            match r.and_then(|r| r) {
                Ok(loaded) => {
                    if let Err(e) = self.set_scene(loaded) {
                        self.errors.report(ErrorKind::Other, e.clone());
                        self.fail_smoke(ctx, e);
                    }
                    if let Some(e) = self.start_error.take() {
                        self.fail_smoke(ctx, e);
                    }
                }
                Err(e) => {
                    self.errors.report(ErrorKind::Other, e.clone());
                    self.fail_smoke(ctx, e);
                }
            }
        }
        if let Some(job) = &mut self.build_job
            && let Some(r) = job.poll()
        {
            self.build_job = None;
            let generation = self.scene.as_ref().map(|s| s.generation);
            match r.and_then(|r| r) {
                // An animation frame waits for the frame on screen to finish.
                Ok(b) if Some(b.scene_generation) == generation && b.pose.is_some() => self.ready = Some(b),
                Ok(b) if Some(b.scene_generation) == generation => self.set_built(b),
                Ok(_) => {} // built for a scene that has been replaced since
                Err(e) if self.posing => {
                    // The pose failed: playback stops there and the error is shown.
                    if let Some(t) = &mut self.timeline {
                        t.playing = false;
                        t.failed = Some(t.wanted());
                    }
                    self.errors.report(ErrorKind::Other, e.clone());
                    self.fail_smoke(ctx, e);
                }
                Err(e) => {
                    self.errors.report(ErrorKind::Build(self.wanted_grid()), e.clone());
                    self.fail_smoke(ctx, e);
                }
            }
        }
        // The frame in flight is only waited for when it shows the same scene (a previous
        // animation frame); one of a replaced scene is never finished (nothing renders it on).
        let same_scene =
            self.built.as_ref().map(|b| b.built.scene_generation) == self.scene.as_ref().map(|s| s.generation);
        if self.ready.is_some() && (!self.viewport.busy() || !same_scene) {
            let b = self.ready.take().expect("a ready frame");
            if Some(b.scene_generation) == self.scene.as_ref().map(|s| s.generation) {
                self.set_built(b);
            }
        }
        // Rebuild when the wanted structure (configuration and pose) differs from the built one
        // (one build at a time; the newest settings win when it finishes).
        if self.build_job.is_none()
            && self.ready.is_none()
            && let Some(scene) = &self.scene
        {
            let want = self.wanted_grid();
            let pose = self.timeline.as_ref().map(|t| t.wanted()).filter(|_| scene.loaded.player.is_some());
            let on_gpu = self.gpu_build().is_some() && gridrt_gpu::build::GridBuilder::supports(&want);
            let have = self.built.as_ref().map(|b| {
                (
                    b.built.scene_generation,
                    b.built.config,
                    b.built.pose.as_ref().map(|p| p.time),
                    b.built.built_on.answers_gpu_build(),
                )
            });
            let failed = self.errors.build_failed(&want)
                || pose.is_some_and(|p| self.timeline.as_ref().and_then(|t| t.failed) == Some(p));
            if have != Some((scene.generation, want, pose, on_gpu)) && !failed {
                self.errors.clear_build();
                let generation = scene.generation;
                self.posing = pose.is_some();
                let gpu = self.gpu_build();
                self.build_job = Some(match (pose, &scene.loaded.player) {
                    (Some(time), Some(player)) => {
                        jobs::spawn_pose_build(ctx, player.clone(), time, want, generation, gpu)
                    }
                    _ => jobs::spawn_build(ctx, scene.loaded.tris.clone(), want, generation, None, gpu),
                });
            }
        }
        if self.measure_at_start && self.last_key.is_some() && self.built.is_some() && self.build_job.is_none() {
            self.measure_at_start = false;
            if !self.start_measurement() {
                let why = "--measure: the structure has no sampled cost curve (use a flat or macrocell grid with auto resolution)";
                self.errors.report(ErrorKind::Other, why);
                self.fail_smoke(ctx, why.into());
            }
        }
        self.poll_measurement(ctx);
    }

    /// Makes `loaded` the current scene; when its GPU upload fails the previous scene stays and
    /// the error is returned (natively, a scene beyond the device's buffer limits is kept on the
    /// CPU instead).
    pub(super) fn set_scene(&mut self, loaded: LoadedScene) -> Result<(), String> {
        let (gpu_scene, off_gpu) = match &self.gpu {
            Some(g) => {
                let uploaded = GpuScene::new(&g.ctx, &loaded.tris).and_then(|s| g.ctx.check_device().map(|()| s));
                match held_on_cpu(uploaded) {
                    Ok(kept) => kept,
                    Err(e) => {
                        // Only the browser gets here with a scene too large for the device.
                        let hint = match e {
                            GpuError::BufferTooLarge { .. } => "; the desktop app traces such a scene on the CPU",
                            _ => "",
                        };
                        return Err(format!("{}: {e} (the previous scene stays{hint})", loaded.name));
                    }
                }
            }
            None => (None, None),
        };
        self.scene_generation += 1;
        let aspect = self.last_key.map_or(1.0, |k| k.size[0] as f32 / k.size[1].max(1) as f32);
        self.orbit = match self.initial_camera {
            Some(CameraArg::At(cam)) => Orbit::from_camera(&cam, &loaded.bounds),
            _ => Orbit::fit(&loaded.bounds, aspect),
        };
        // A framed or interior view waits for the first structure (it probes it).
        self.initial_camera = self.initial_camera.filter(|c| matches!(c, CameraArg::Framed | CameraArg::Interior));
        self.timeline = self.start_timeline(&loaded);
        self.ready = None;
        self.scene = Some(SceneState { loaded, gpu: gpu_scene, off_gpu, generation: self.scene_generation });
        self.measurement = Default::default();
        self.errors.clear_build();
        Ok(())
    }

    /// The timeline of a newly opened scene: its first clip from the start, playing, unless
    /// the command line chose otherwise for the first animated scene. `None` without clips.
    fn start_timeline(&mut self, loaded: &LoadedScene) -> Option<Timeline> {
        let Some(player) = loaded.player.as_ref() else {
            if let Some(key) = self.animation_start.clip.take() {
                let e = format!("--animation {key}: {} has no animations", loaded.name);
                self.errors.report(ErrorKind::Other, e.clone());
                self.start_error = Some(e);
            }
            return None;
        };
        let start = std::mem::take(&mut self.animation_start);
        let clip = match &start.clip {
            Some(key) => {
                let found = player
                    .lock()
                    .map_err(|_| "the posing state is poisoned".to_string())
                    .and_then(|p| p.rig.find_clip(key).map_err(|e| e.to_string()));
                match found {
                    Ok(c) => c,
                    Err(e) => {
                        self.errors.report(ErrorKind::Other, format!("--animation: {e}"));
                        self.start_error = Some(e);
                        0
                    }
                }
            }
            None => 0,
        };
        let c = loaded.clips.get(clip)?;
        Some(Timeline::new(clip, c.clamp(start.seconds.unwrap_or(c.start)), !start.paused))
    }

    /// The structure the settings ask for, as it is built ([`as_built`]).
    fn wanted_grid(&self) -> GridConfig {
        as_built(self.settings.grid, self.cpu_traces())
    }

    /// Natively, why the frames are traced on the CPU whatever the settings: the device cannot
    /// hold the scene, or the structure on screen (one of this scene's).
    pub(super) fn off_gpu(&self) -> Option<&str> {
        let scene = self.scene.as_ref()?;
        let built = self.built.as_ref().filter(|b| b.built.scene_generation == scene.generation);
        scene.off_gpu.as_deref().or_else(|| built.and_then(|b| b.off_gpu.as_deref()))
    }

    /// Whether the CPU traces the frames: the settings ask for it (or for auto, on a software
    /// adapter), or the device cannot hold what is on screen ([`GridrtApp::off_gpu`]).
    pub(super) fn cpu_traces(&self) -> bool {
        self.settings.cpu_traces(self.software_adapter()) || self.off_gpu().is_some()
    }

    /// Whether the adapter runs on the CPU's own cores (lavapipe, SwiftShader, WARP).
    pub(super) fn software_adapter(&self) -> bool {
        self.gpu.as_ref().is_some_and(|g| g.ctx.is_software())
    }

    /// The device to build on when the settings ask for GPU builds (not for a scene it cannot
    /// hold).
    fn gpu_build(&self) -> Option<crate::gui::built::GpuBuild> {
        if !self.settings.gpu_build || self.scene.as_ref().is_some_and(|s| s.off_gpu.is_some()) {
            return None;
        }
        self.gpu.as_ref().map(|g| crate::gui::built::GpuBuild { ctx: g.ctx.clone(), builder: g.builder.clone() })
    }

    pub(super) fn set_built(&mut self, mut built: Built) {
        self.worker_builds += u64::from(built.built_on == BuiltOn::Worker);
        if let Some(on_gpu) = built.on_gpu.take() {
            // Built on the device: the structure and the triangles are used as they are.
            let posed_gpu = built.pose.is_some().then_some(on_gpu.scene);
            self.built_counter += 1;
            let upload_ms = on_gpu.upload_ms;
            self.built = Some(BuiltState {
                built,
                gpu: Some(on_gpu.structure),
                posed_gpu,
                upload_ms,
                off_gpu: None,
                id: self.built_counter,
            });
            return;
        }
        let started = web_time::Instant::now();
        let scene_on_gpu = self.scene.as_ref().is_some_and(|s| s.off_gpu.is_none());
        let uploaded = match &self.gpu {
            Some(g) if scene_on_gpu => {
                let posed = built.pose.as_ref().map(|p| GpuScene::new(&g.ctx, &p.tris)).transpose();
                let structure = GpuStructure::new(&g.ctx, &built.grid);
                let both = match (posed, structure) {
                    (Ok(p), Ok(s)) => g.ctx.check_device().map(|()| (s, p)),
                    (Err(e), _) | (_, Err(e)) => Err(e),
                };
                held_on_cpu(both)
            }
            // The device holds nothing of a scene it could not hold.
            _ => Ok((None, None)),
        };
        let (on_device, off_gpu) = match uploaded {
            Ok(u) => u,
            Err(e) => {
                // The previous structure stays on screen; this configuration is not retried.
                self.errors.report(
                    ErrorKind::Build(built.config),
                    format!("uploading the {} grid: {e} (the previous one stays)", built.config.kind),
                );
                return;
            }
        };
        let (gpu, posed_gpu) = on_device.map_or((None, None), |(s, p)| (Some(s), p));
        self.built_counter += 1;
        let upload_ms = started.elapsed().as_secs_f64() * 1e3;
        self.built = Some(BuiltState { built, gpu, posed_gpu, upload_ms, off_gpu, id: self.built_counter });
        // `--camera framed|interior`: aimed with the first structure.
        if let Some(view) = self.initial_camera.take() {
            self.view_camera(view);
        }
    }
}

/// What an upload gave: the value, or natively for a buffer beyond the device's limits nothing
/// and why (the CPU then holds and traces it; the browser has no CPU tracing, so there it is an
/// error like any other).
fn held_on_cpu<T>(uploaded: Result<T, GpuError>) -> Result<(Option<T>, Option<String>), GpuError> {
    match uploaded {
        Ok(v) => Ok((Some(v), None)),
        Err(GpuError::BufferTooLarge { buffer, size, limit, which }) if cfg!(not(target_arch = "wasm32")) => {
            let (size, limit) = (human_bytes(size), human_bytes(limit));
            Ok((
                None,
                Some(format!(
                    "traced on the CPU: the device cannot hold the {buffer} ({size}; its {which} is {limit})"
                )),
            ))
        }
        Err(e) => Err(e),
    }
}

/// `grid` as the app builds it when the CPU traces (`cpu_trace`) or the GPU does: under auto,
/// cell slabs only for the CPU (the GPU kernels never read them, so a rebuild every frame would
/// pay for nothing; switching to CPU tracing rebuilds with them).
fn as_built(mut grid: GridConfig, cpu_trace: bool) -> GridConfig {
    if grid.cell_planes == CellPlanes::Auto && !cpu_trace {
        grid.cell_planes = CellPlanes::Off;
    }
    grid
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slabs_under_auto_only_for_cpu_tracing() {
        let auto = GridConfig::default();
        assert_eq!(auto.cell_planes, CellPlanes::Auto);
        assert_eq!(as_built(auto, true), auto);
        assert_eq!(as_built(auto, false), GridConfig { cell_planes: CellPlanes::Off, ..auto });
        for explicit in [CellPlanes::On, CellPlanes::Off] {
            let g = GridConfig { cell_planes: explicit, ..auto };
            assert_eq!((as_built(g, true), as_built(g, false)), (g, g));
        }
    }
}
