//! A loaded scene played frame by frame: the rig, the posed mesh and its triangle soup, with
//! every buffer reused from one frame to the next. Shared by `gridrt animate`, `gridrt bench
//! --dynamic` and the app's timeline.

use glam::Vec3;

use super::{ClipTime, PoseScratch, Rig};
use crate::error::SceneError;
use crate::gltf_load::Loaded;
use crate::mesh::{Aabb, Mesh};

/// A loaded scene posed frame by frame.
#[derive(Debug)]
pub struct Player {
    pub rig: Rig,
    pub mesh: Mesh,
    /// The posed triangles, in the loader's triangle order.
    pub tris: Vec<[Vec3; 3]>,
    /// The clip [`Player::pose`] samples.
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

    /// Poses the mesh at `seconds` of the current clip and refreshes the triangles.
    pub fn pose(&mut self, seconds: f64) -> Result<(), SceneError> {
        let time = ClipTime { clip: self.clip, seconds };
        self.rig.pose(Some(time), &mut self.scratch, &mut self.mesh.positions)?;
        self.mesh.triangles_into(&mut self.tris);
        Ok(())
    }

    /// The union of the bounds at `samples` + 1 evenly spaced times over the current clip (for a
    /// camera and a light that stay put while the scene moves). Leaves the mesh posed at the
    /// clip's start.
    pub fn clip_bounds(&mut self, samples: u32) -> Result<Aabb, SceneError> {
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
