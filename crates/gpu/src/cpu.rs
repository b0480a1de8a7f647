//! CPU ports of the render kernels (same names, same arithmetic as shaders/camera.wgsl,
//! shadow.wgsl and shade.wgsl), used to render reference images and test the GPU output.
//! The trace kernels' CPU ports live in `gridrt-grid` (each kernel names its port).

use glam::Vec3;
use gridrt_scene::{Camera, Ray};

use crate::layout::GpuCamera;

/// The camera constants the render kernels read.
pub fn gpu_camera(cam: &Camera, width: u32, height: u32) -> GpuCamera {
    let fwd = (cam.target - cam.eye).normalize();
    let up0 = if fwd.cross(cam.up).length_squared() < 1e-12 { Vec3::Z } else { cam.up };
    let right = fwd.cross(up0).normalize();
    let up = right.cross(fwd);
    let half_v = (cam.vfov_deg.to_radians() * 0.5).tan();
    GpuCamera {
        eye: cam.eye.extend(half_v).to_array(),
        right: right.extend(width as f32).to_array(),
        up: up.extend(height as f32).to_array(),
        forward: fwd.extend(width as f32 / height as f32).to_array(),
    }
}

/// shaders/shared/render_bindings.wgsl `camera_ray`.
pub fn camera_ray(cam: &GpuCamera, x: u32, y: u32) -> Ray {
    let w = cam.right[3];
    let h = cam.up[3];
    let half_v = cam.eye[3];
    let half_h = half_v * cam.forward[3];
    let sx = ((x as f32 + 0.5) / w * 2.0 - 1.0) * half_h;
    let sy = (1.0 - (y as f32 + 0.5) / h * 2.0) * half_v;
    let v3 = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
    let d = v3(cam.forward) + v3(cam.right) * sx + v3(cam.up) * sy;
    Ray::new(v3(cam.eye), d, 0.0, f32::INFINITY)
}

/// All primary rays of the image, row-major.
pub fn camera_rays(cam: &GpuCamera) -> Vec<Ray> {
    let (w, h) = (cam.right[3] as u32, cam.up[3] as u32);
    (0..h).flat_map(|y| (0..w).map(move |x| camera_ray(cam, x, y))).collect()
}
