//! The viewer's camera: orbit around a target, pan, zoom; reset frames the scene bounds the way
//! `--camera auto` does ([`Camera::fit`]).

use glam::Vec3;
use gridrt_scene::scaled::{length_scaled, normalize_scaled};
use gridrt_scene::{Aabb, Camera};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub target: Vec3,
    /// Radians around +Y, 0 looking down −Z.
    pub yaw: f32,
    /// Radians above the horizon.
    pub pitch: f32,
    pub distance: f32,
    pub vfov_deg: f32,
    /// Scene size, for pan speed and zoom limits.
    pub scale: f32,
}

/// Pitch stops short of the poles, where the up vector would flip.
const MAX_PITCH: f32 = 1.55;

impl Orbit {
    /// The orbit matching [`Camera::fit`] for these bounds and aspect.
    pub fn fit(bounds: &Aabb, aspect: f32) -> Orbit {
        Orbit::from_camera(&Camera::fit(bounds, aspect), bounds)
    }

    /// The orbit through a given camera (its eye, target and field of view).
    pub fn from_camera(cam: &Camera, bounds: &Aabb) -> Orbit {
        let offset = cam.eye - cam.target;
        // Any scene scale: no absolute floor (a scene nanometres across keeps its distances).
        let distance = length_scaled(offset).max(f32::MIN_POSITIVE);
        let dir = normalize_scaled(offset);
        Orbit {
            target: cam.target,
            yaw: dir.x.atan2(dir.z),
            pitch: dir.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH),
            distance,
            vfov_deg: cam.vfov_deg,
            scale: bounds.diagonal().max(distance),
        }
    }

    pub fn camera(&self) -> Camera {
        let dir = Vec3::new(self.pitch.cos() * self.yaw.sin(), self.pitch.sin(), self.pitch.cos() * self.yaw.cos());
        Camera { eye: self.target + dir * self.distance, target: self.target, up: Vec3::Y, vfov_deg: self.vfov_deg }
    }

    /// Rotates by screen-space angles (radians).
    pub fn rotate(&mut self, d_yaw: f32, d_pitch: f32) {
        self.yaw -= d_yaw;
        self.pitch = (self.pitch + d_pitch).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the target in the view plane by a fraction of the view height.
    pub fn pan(&mut self, dx: f32, dy: f32) {
        let cam = self.camera();
        let fwd = cam.forward();
        let right = fwd.cross(Vec3::Y).normalize_or(Vec3::X);
        let up = right.cross(fwd);
        let h = 2.0 * self.distance * (self.vfov_deg.to_radians() * 0.5).tan();
        self.target += (-right * dx + up * dy) * h;
    }

    /// Multiplies the distance by `factor`, within sane limits of the scene size.
    pub fn zoom(&mut self, factor: f32) {
        self.distance = (self.distance * factor).clamp(self.scale * 1e-4, self.scale * 100.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The orbit of a scene nanometres or light years across is the orbit at scale 1, scaled
    /// (no absolute floor on its distance or zoom), and it still zooms.
    #[test]
    fn orbits_keep_their_shape_at_every_scale() {
        let b = Aabb { min: Vec3::splat(-1.0), max: Vec3::new(3.0, 1.0, 1.0) };
        let o = Orbit::fit(&b, 1.5);
        for k in [-100, -60, 60, 100] {
            let s = 2f32.powi(k);
            let mut so = Orbit::fit(&Aabb { min: b.min * s, max: b.max * s }, 1.5);
            assert_eq!((so.yaw, so.pitch), (o.yaw, o.pitch), "2^{k}");
            assert!((so.distance / s - o.distance).abs() <= 1e-6 * o.distance, "2^{k}: {}", so.distance);
            let d = so.distance;
            so.zoom(0.5);
            assert!((so.distance - d * 0.5).abs() <= 1e-6 * d, "2^{k}: zoom {d} → {}", so.distance);
        }
    }

    #[test]
    fn an_orbit_reproduces_its_camera_and_moves_sensibly() {
        let bounds = Aabb { min: Vec3::splat(-1.0), max: Vec3::new(3.0, 1.0, 1.0) };
        let fit = Camera::fit(&bounds, 1.5);
        let mut o = Orbit::fit(&bounds, 1.5);
        let c = o.camera();
        assert!((c.eye - fit.eye).length() < 1e-4 && c.target == fit.target, "{c:?} vs {fit:?}");
        let d0 = (c.eye - c.target).length();
        o.zoom(0.5);
        assert!(((o.camera().eye - o.camera().target).length() - d0 * 0.5).abs() < 1e-4);
        o.rotate(0.0, 10.0);
        assert!(o.pitch <= MAX_PITCH, "pitch is clamped short of the pole");
        let before = o.target;
        o.pan(0.1, 0.0);
        assert!((o.target - before).length() > 0.0 && (o.target - before).y.abs() < 1e-5);
    }
}
