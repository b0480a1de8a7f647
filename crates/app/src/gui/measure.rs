//! The cost-model window's measurement: a flat grid at each resolution the cost model sampled
//! is built off the UI thread and rendered once, timed, so the plot shows the measured frame
//! time beside the model's curve.

use eframe::egui;
#[cfg(not(target_arch = "wasm32"))]
use gridrt_gpu::upload::GpuStructure;
use gridrt_grid::{GridConfig, GridKind, Resolution};

#[cfg(not(target_arch = "wasm32"))]
use gridrt_gpu::FrameSource;

use super::GridrtApp;
use super::built::{Built, build_structure};
use super::cost_plot;
use super::errors::ErrorKind;
use super::jobs::Job;

impl GridrtApp {
    /// Starts timing a flat grid at each resolution the cost model sampled (false when the
    /// current structure has no sampled curve).
    pub(super) fn start_measurement(&mut self) -> bool {
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
    pub(super) fn poll_measurement(&mut self, ctx: &egui::Context) {
        if let Some(job) = &mut self.measure_job
            && let Some(r) = job.poll()
        {
            self.measure_job = None;
            match r.and_then(|r| r) {
                Ok(b) => self.time_frame(&b),
                Err(e) => {
                    self.errors.report(ErrorKind::Other, e);
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
            self.measure_job = Some(Job::spawn("measuring", ctx, move || build_structure(&tris, &cfg, generation)));
        }
    }

    #[cfg(not(target_arch = "wasm32"))]
    pub(super) fn time_frame(&mut self, b: &Built) {
        let res = self.measurement.pending.remove(0);
        let (Some(gpu), Some(scene), Some(key)) = (&self.gpu, &self.scene, self.last_key) else { return };
        let Some(gs) = &scene.gpu else {
            let why = scene.off_gpu.as_deref().unwrap_or("the scene is not on the device");
            self.errors.report(ErrorKind::Other, format!("frame-time measurement needs the GPU: {why}"));
            self.measurement.pending.clear();
            return;
        };
        let s = match GpuStructure::new(&gpu.ctx, &b.grid) {
            Ok(s) => s,
            Err(e) => {
                self.errors.report(ErrorKind::Other, e.to_string());
                return;
            }
        };
        let opts = self.render_options(key.camera, key.size);
        match self.viewport.render_blocking(
            gpu,
            &FrameSource { scene: gs, structure: &s, bounds: &scene.loaded.bounds },
            &opts,
        ) {
            Ok(ms) => {
                let m = (res[0] as f64 * res[1] as f64 * res[2] as f64).cbrt();
                self.measurement.results.push((m, ms));
            }
            Err(e) => {
                self.viewport.cancel();
                self.errors.report(ErrorKind::Other, e.to_string());
            }
        }
        // The measured frame replaced the image: render the real structure again.
        self.last_key = None;
    }

    #[cfg(target_arch = "wasm32")]
    pub(super) fn time_frame(&mut self, _b: &Built) {
        // Timing needs a blocking wait, which the browser does not allow.
        self.measurement.pending.clear();
        self.errors.report(ErrorKind::Other, "frame-time measurement is not available in the browser");
    }
}
