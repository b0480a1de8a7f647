//! A pinhole camera and the framing used by `--camera auto`.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::mesh::Aabb;
use crate::ray::Ray;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
}

impl Camera {
    /// Frames `bounds` for an image of the given aspect (width / height): looks at the centre
    /// from a fixed oblique direction, far enough that the bounding sphere fits the narrower
    /// field of view.
    pub fn fit(bounds: &Aabb, aspect: f32) -> Camera {
        let vfov_deg = 45.0f32;
        let center = bounds.center();
        let radius = (bounds.diagonal() * 0.5).max(1e-6);
        let half_v = (vfov_deg.to_radians() * 0.5).tan();
        let half = half_v.min(half_v * aspect).atan();
        let dist = radius / half.sin() * 1.02;
        let dir = Vec3::new(0.55, 0.45, 1.0).normalize();
        Camera { eye: center + dir * dist, target: center, up: Vec3::Y, vfov_deg }
    }

    /// Parses `eye_x,eye_y,eye_z,target_x,target_y,target_z,fov`: the `--camera` syntax.
    pub fn parse(s: &str) -> Result<Camera, String> {
        let v: Vec<f32> = s
            .split(',')
            .map(|x| x.trim().parse::<f32>().map_err(|e| format!("\"{x}\": {e}")))
            .collect::<Result<_, _>>()?;
        if v.len() != 7 || v.iter().any(|x| !x.is_finite()) {
            return Err(format!(
                "expected 7 finite numbers eye_x,eye_y,eye_z,target_x,target_y,target_z,fov; got \"{s}\""
            ));
        }
        let cam = Camera {
            eye: Vec3::new(v[0], v[1], v[2]),
            target: Vec3::new(v[3], v[4], v[5]),
            up: Vec3::Y,
            vfov_deg: v[6],
        };
        // The view direction must survive normalisation in f32 (1e-30 apart underflows to NaN).
        if (cam.target - cam.eye).normalize_or_zero() == Vec3::ZERO {
            return Err(format!("eye and target are the same point or too close to give a view direction: \"{s}\""));
        }
        if !(0.01..179.0).contains(&cam.vfov_deg) {
            return Err(format!("fov must be in (0, 179) degrees, got {}", cam.vfov_deg));
        }
        Ok(cam)
    }

    /// Orthonormal basis (right, up, forward) with a fallback up vector when looking along it.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let fwd = (self.target - self.eye).normalize();
        let up = if fwd.cross(self.up).length_squared() < 1e-12 { Vec3::Z } else { self.up };
        let right = fwd.cross(up).normalize();
        (right, right.cross(fwd), fwd)
    }

    /// The ray through the centre of pixel (x, y) of a `width`×`height` image, row 0 at the top.
    pub fn ray(&self, x: u32, y: u32, width: u32, height: u32) -> Ray {
        let (right, up, fwd) = self.basis();
        let half_v = (self.vfov_deg.to_radians() * 0.5).tan();
        let half_h = half_v * width as f32 / height as f32;
        let sx = ((x as f32 + 0.5) / width as f32 * 2.0 - 1.0) * half_h;
        let sy = (1.0 - (y as f32 + 0.5) / height as f32 * 2.0) * half_v;
        Ray::new(self.eye, fwd + right * sx + up * sy, 0.0, f32::INFINITY)
    }
}
