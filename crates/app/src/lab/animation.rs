//! A scene playing an animation, for `gridrt animate` and `gridrt bench --dynamic`: the rig,
//! the posed mesh and its triangle soup (buffers reused frame to frame), the clip's looped
//! time line, a view (camera, light, primary rays) fixed over the whole clip, and the CPU
//! shadow rays.

use glam::Vec3;
use gridrt_gpu::RenderOptions;
use gridrt_gpu::layout::ShadeParams;
use gridrt_grid::trace::TraceOptions;
use gridrt_scene::{Aabb, ClipTime, Hit, Loaded, Mesh, PoseScratch, Ray, Rig};
use rayon::prelude::*;

/// A loaded scene posed frame by frame.
#[derive(Debug)]
pub struct Player {
    pub rig: Rig,
    pub mesh: Mesh,
    /// The posed triangles, in the loader's triangle order.
    pub tris: Vec<[Vec3; 3]>,
    pub clip: usize,
    scratch: PoseScratch,
}

impl Player {
    pub fn new(loaded: Loaded, clip: usize) -> Player {
        let Loaded { rig, mesh, .. } = loaded;
        let tris = mesh.triangles();
        Player { rig, mesh, tris, clip, scratch: PoseScratch::default() }
    }

    /// The clip time of frame `k` at `fps`, starting at `first` (clip time), looped.
    pub fn frame_time(&self, first: f64, k: u32, fps: f64) -> f64 {
        let c = &self.rig.clips()[self.clip];
        c.looped(first - c.start + k as f64 / fps)
    }

    /// Poses the mesh at `seconds` and refreshes the triangles.
    pub fn pose(&mut self, seconds: f64) -> anyhow::Result<()> {
        let time = ClipTime { clip: self.clip, seconds };
        self.rig.pose(Some(time), &mut self.scratch, &mut self.mesh.positions)?;
        self.mesh.triangles_into(&mut self.tris);
        Ok(())
    }

    /// The union of the bounds at `samples` times over the clip (for a camera and a light that
    /// stay put while the scene moves). Leaves the mesh posed at the clip's start.
    pub fn clip_bounds(&mut self, samples: u32) -> anyhow::Result<Aabb> {
        let c = self.rig.clips()[self.clip].clone();
        let mut b = Aabb::EMPTY;
        for k in 0..=samples {
            self.pose(c.start + c.duration() * k as f64 / samples.max(1) as f64)?;
            b = b.union(&self.mesh.bounds());
        }
        self.pose(c.start)?;
        Ok(b)
    }
}

/// What every frame of a clip is seen with: the shaded render's options (camera framing the
/// clip's bounds), its light and shading constants, and its primary rays.
#[derive(Debug)]
pub struct FixedView {
    pub opts: RenderOptions,
    pub shade: ShadeParams,
    pub primary: Vec<Ray>,
}

impl FixedView {
    pub fn new(bounds: &Aabb, width: u32, height: u32) -> FixedView {
        let opts = RenderOptions::fit(bounds, width, height);
        let shade = gridrt_gpu::render::shade_params(bounds, &opts);
        let primary = gridrt_gpu::cpu::camera_rays(&gridrt_gpu::cpu::gpu_camera(&opts.camera, width, height));
        FixedView { opts, shade, primary }
    }

    /// The render's traversal and mailbox, for CPU traces of the same frame.
    pub fn trace_options(&self) -> TraceOptions {
        TraceOptions { traversal: self.opts.traversal, mailbox: self.opts.mailbox }
    }
}

/// shaders/shadow.wgsl's shadow rays (the CPU port), for every primary ray, in parallel.
pub fn shadow_rays(shade: &ShadeParams, primary: &[Ray], hits: &[Hit], out: &mut Vec<Ray>) {
    out.clear();
    primary.par_iter().zip(hits).map(|(r, h)| gridrt_gpu::cpu::shadow_ray(shade, r, h)).collect_into_vec(out);
}
