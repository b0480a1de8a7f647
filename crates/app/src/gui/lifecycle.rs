//! The app's document lifecycle: a scene is loaded off the UI thread and uploaded, the
//! structure the settings ask for is built off the UI thread and uploaded; a failure keeps the
//! previous scene or structure on screen and is reported. An animated scene is posed at the
//! timeline's time and rebuilt with every pose; a finished frame waits until the frame on
//! screen is complete, so every pose built is shown.

use eframe::egui;
use gridrt_gpu::upload::{GpuScene, GpuStructure};
use gridrt_grid::GridConfig;
use gridrt_grid::cell_plane::CellPlanes;

use super::GridrtApp;
use super::errors::ErrorKind;
use super::jobs::{self, Job, LoadedScene, SceneSource};
use super::orbit::Orbit;
use super::timeline::Timeline;
use crate::cli::CameraArg;
use crate::gui::built::{Built, BuiltOn};

#[derive(Debug)]
pub(super) struct SceneState {
    pub(super) loaded: LoadedScene,
    pub(super) gpu: Option<GpuScene>,
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
                    b.built.built_on == BuiltOn::Gpu,
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
    /// the error is returned.
    pub(super) fn set_scene(&mut self, loaded: LoadedScene) -> Result<(), String> {
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
        self.orbit = match self.initial_camera {
            Some(CameraArg::At(cam)) => Orbit::from_camera(&cam, &loaded.bounds),
            _ => Orbit::fit(&loaded.bounds, aspect),
        };
        // A framed or interior view waits for the first structure (it probes it).
        self.initial_camera = self.initial_camera.filter(|c| matches!(c, CameraArg::Framed | CameraArg::Interior));
        self.timeline = self.start_timeline(&loaded);
        self.ready = None;
        self.scene = Some(SceneState { loaded, gpu: gpu_scene, generation: self.scene_generation });
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
        as_built(self.settings.grid, self.settings.cpu_traces())
    }

    /// The device to build on when the settings ask for GPU builds.
    fn gpu_build(&self) -> Option<crate::gui::built::GpuBuild> {
        if !self.settings.gpu_build {
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
            self.built =
                Some(BuiltState { built, gpu: Some(on_gpu.structure), posed_gpu, upload_ms, id: self.built_counter });
            return;
        }
        let started = web_time::Instant::now();
        let uploaded = match &self.gpu {
            Some(g) => {
                let posed = built.pose.as_ref().map(|p| GpuScene::new(&g.ctx, &p.tris)).transpose();
                let structure = GpuStructure::new(&g.ctx, &built.grid);
                match (posed, structure) {
                    (Ok(p), Ok(s)) => g.ctx.check_device().map(|()| (Some(s), p)),
                    (Err(e), _) | (_, Err(e)) => Err(e),
                }
            }
            None => Ok((None, None)),
        };
        let (gpu, posed_gpu) = match uploaded {
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
        self.built_counter += 1;
        let upload_ms = started.elapsed().as_secs_f64() * 1e3;
        self.built = Some(BuiltState { built, gpu, posed_gpu, upload_ms, id: self.built_counter });
        // `--camera framed|interior`: aimed with the first structure.
        if let Some(view) = self.initial_camera.take() {
            self.view_camera(view);
        }
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
