//! The app's document lifecycle: a scene is loaded off the UI thread and uploaded, the
//! structure the settings ask for is built off the UI thread and uploaded; a failure keeps the
//! previous scene or structure on screen and is reported.

use eframe::egui;
use gridrt_gpu::upload::{GpuScene, GpuStructure};

use super::GridrtApp;
use super::errors::ErrorKind;
use super::jobs::{self, Job, LoadedScene, SceneSource};
use super::orbit::Orbit;
use crate::gui::built::Built;

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
            match r.and_then(|r| r) {
                Ok(b) if Some(b.scene_generation) == self.scene.as_ref().map(|s| s.generation) => self.set_built(b),
                Ok(_) => {} // built for a scene that has been replaced since
                Err(e) => {
                    self.errors.report(ErrorKind::Build(self.settings.grid), e.clone());
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
            let failed = self.errors.build_failed(&want);
            if have != Some((scene.generation, want)) && !failed {
                self.errors.clear_build();
                let tris = scene.loaded.tris.clone();
                let generation = scene.generation;
                self.build_job = Some(jobs::spawn_build(ctx, tris, want, generation));
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
        self.orbit = match self.initial_camera.take() {
            Some(cam) => Orbit::from_camera(&cam, &loaded.bounds),
            None => Orbit::fit(&loaded.bounds, aspect),
        };
        self.scene = Some(SceneState { loaded, gpu: gpu_scene, generation: self.scene_generation });
        self.measurement = Default::default();
        self.errors.clear_build();
        Ok(())
    }

    pub(super) fn set_built(&mut self, built: Built) {
        self.worker_builds += u64::from(built.in_worker);
        let gpu = match &self.gpu {
            Some(g) => match GpuStructure::new(&g.ctx, &built.grid).and_then(|s| g.ctx.check_device().map(|()| s)) {
                Ok(s) => Some(s),
                Err(e) => {
                    // The previous structure stays on screen; this configuration is not retried.
                    self.errors.report(
                        ErrorKind::Build(built.config),
                        format!("uploading the {} grid: {e} (the previous one stays)", built.config.kind),
                    );
                    return;
                }
            },
            None => None,
        };
        self.built_counter += 1;
        self.built = Some(BuiltState { built, gpu, id: self.built_counter });
    }
}
