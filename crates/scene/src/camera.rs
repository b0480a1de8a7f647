//! A pinhole camera and the framing used by `--camera auto`.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::mesh::Aabb;
use crate::ray::Ray;

/// The radius [`Camera::fit`] gives a box of no extent, relative to its largest coordinate.
const EMPTY_BOX_RADIUS: f32 = 1.0 / (1u32 << 20) as f32;

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
        // Any scale: a scene a few nanometres across is framed as one a few kilometres across.
        // Only a box of no extent (one point) gets a radius of its own, relative to where it is.
        let radius = bounds.diagonal() * 0.5;
        let radius = if radius > 0.0 && radius.is_finite() {
            radius
        } else {
            (center.abs().max_element() * EMPTY_BOX_RADIUS).max(f32::MIN_POSITIVE)
        };
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
        if cam.forward() == Vec3::ZERO {
            return Err(format!(
                "eye and target are the same point, or too far apart for f32, to give a view direction: \"{s}\""
            ));
        }
        if !(0.01..179.0).contains(&cam.vfov_deg) {
            return Err(format!("fov must be in (0, 179) degrees, got {}", cam.vfov_deg));
        }
        Ok(cam)
    }

    /// The unit view direction, or zero when eye and target coincide or their difference
    /// overflows f32, at any distance ([`crate::scaled::normalize_scaled`]: eye and target 1e30
    /// or 1e-30 apart).
    pub fn forward(&self) -> Vec3 {
        crate::scaled::normalize_scaled(self.target - self.eye)
    }

    /// Orthonormal basis (right, up, forward) with a fallback up vector when looking along it.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let fwd = self.forward();
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The framing camera of a box scaled by a power of two is the same camera scaled alike,
    /// from 2^-120 to 2^100: no absolute floor on its distance, no overflow of the diagonal. A
    /// box of one point still gets a camera that looks at it.
    #[test]
    fn fit_frames_every_scale_alike() {
        let b = Aabb { min: Vec3::new(-1.0, 0.5, -2.0), max: Vec3::new(3.0, 2.0, 1.0) };
        let c = Camera::fit(&b, 1.5);
        for k in (-120..=100).step_by(10) {
            let s = 2f32.powi(k);
            let f = Camera::fit(&Aabb { min: b.min * s, max: b.max * s }, 1.5);
            assert_eq!((f.eye / s, f.target / s, f.forward()), (c.eye, c.target, c.forward()), "2^{k}");
        }
        for p in [Vec3::ZERO, Vec3::new(1e-30, 0.0, 0.0), Vec3::splat(1e30)] {
            let cam = Camera::fit(&Aabb { min: p, max: p }, 1.0);
            assert!(cam.eye.is_finite() && cam.eye != p && cam.forward() != Vec3::ZERO, "{p}: {cam:?}");
        }
    }

    /// The view direction of cameras whose eye-to-target distance squared leaves f32 (1e30 and
    /// 1e-30 apart) is still the unit direction; coincident or overflowing ones have none.
    #[test]
    fn forward_survives_extreme_distances() {
        let cam = |eye: Vec3, target: Vec3| Camera { eye, target, up: Vec3::Y, vfov_deg: 60.0 };
        for s in [1e30f32, 1e-30, 1.0] {
            let f = cam(Vec3::new(s, 0.0, 0.0), Vec3::ZERO).forward();
            assert!((f - -Vec3::X).length() < 1e-6, "{s}: {f}");
            let f = cam(Vec3::ZERO, Vec3::new(s, s, 0.0)).forward();
            assert!((f.length() - 1.0).abs() < 1e-6 && f.z == 0.0, "{s}: {f}");
        }
        assert_eq!(cam(Vec3::ONE, Vec3::ONE).forward(), Vec3::ZERO);
        assert_eq!(cam(Vec3::splat(3e38), Vec3::splat(-3e38)).forward(), Vec3::ZERO);
        assert!(Camera::parse("1e30,0,0,0,0,0,60").is_ok());
        assert!(Camera::parse("3e38,0,0,-3e38,0,0,60").is_err());
    }
}
