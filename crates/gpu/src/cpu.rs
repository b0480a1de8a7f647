//! CPU ports of the render kernels (same names, same arithmetic as shaders/camera.wgsl,
//! shadow.wgsl, shade.wgsl and present.wgsl), used to render reference images and test the GPU
//! output pixel by pixel.
//! The trace kernels' CPU ports live in `gridrt-grid` (each kernel names its port).

use glam::Vec3;
use gridrt_scene::scaled::{length_scaled, normalize_scaled};
use gridrt_scene::{Camera, Ray};

use crate::layout::GpuCamera;
use crate::view::View;

/// The camera constants the render kernels read.
pub fn gpu_camera(cam: &Camera, width: u32, height: u32) -> GpuCamera {
    let (right, up, fwd) = cam.basis();
    let half_v = (cam.vfov_deg.to_radians() * 0.5).tan();
    GpuCamera {
        eye: cam.eye.to_array(),
        tan_half_vfov: half_v,
        right: right.to_array(),
        width: width as f32,
        up: up.to_array(),
        height: height as f32,
        forward: fwd.to_array(),
        aspect: width as f32 / height as f32,
    }
}

/// shaders/shared/render_bindings.wgsl `camera_ray`.
pub fn camera_ray(cam: &GpuCamera, x: u32, y: u32) -> Ray {
    let half_v = cam.tan_half_vfov;
    let half_h = half_v * cam.aspect;
    let sx = ((x as f32 + 0.5) / cam.width * 2.0 - 1.0) * half_h;
    let sy = (1.0 - (y as f32 + 0.5) / cam.height * 2.0) * half_v;
    let d = Vec3::from(cam.forward) + Vec3::from(cam.right) * sx + Vec3::from(cam.up) * sy;
    Ray::new(Vec3::from(cam.eye), d, 0.0, f32::INFINITY)
}

/// All primary rays of the image, row-major.
pub fn camera_rays(cam: &GpuCamera) -> Vec<Ray> {
    let (w, h) = (cam.width as u32, cam.height as u32);
    (0..h).flat_map(|y| (0..w).map(move |x| camera_ray(cam, x, y))).collect()
}

/// shaders/present.wgsl's sums over a frame's primary rays.
pub fn present_totals(hits: &[gridrt_scene::Hit], stats: &[gridrt_grid::RayStats]) -> crate::layout::FrameTotals {
    let cells: u64 = stats.iter().map(|s| s.cells as u64).sum();
    let tests: u64 = stats.iter().map(|s| s.tests as u64).sum();
    let split = |v: u64| [v as u32, (v >> 32) as u32];
    crate::layout::FrameTotals {
        cells: split(cells),
        tests: split(tests),
        hits: hits.iter().filter(|h| h.is_hit()).count() as u32,
        rays: stats.len() as u32,
        pad: [0; 2],
    }
}

/// shaders/shadow.wgsl `shadow_rays_from_hits` for one pixel: the ray from the light to just
/// before the hit, or an empty ray (tmin > tmax) for a miss.
pub fn shadow_ray(shade: &crate::layout::ShadeParams, primary: &Ray, hit: &gridrt_scene::Hit) -> Ray {
    if !hit.is_hit() {
        return Ray::new(Vec3::ZERO, Vec3::X, 1.0, 0.0);
    }
    let p = primary.at(hit.t);
    let light = Vec3::from(shade.light);
    let from_light = p - light;
    let eps = 1e-4 * shade.diagonal / length_scaled(from_light).max(f32::MIN_POSITIVE);
    Ray::new(light, from_light, 0.0, 1.0 - eps)
}

fn pack_rgba(c: Vec3) -> u32 {
    let q = (c.clamp(Vec3::ZERO, Vec3::ONE) * 255.0 + 0.5).as_uvec3();
    q.x | (q.y << 8) | (q.z << 16) | (255 << 24)
}

/// shaders/shade.wgsl `heat`: black → blue → cyan → green → yellow → red → white at x = 1.
pub fn heat(x: f32) -> Vec3 {
    const STOPS: [Vec3; 7] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 1.0),
    ];
    let s = x.clamp(0.0, 1.0) * 6.0;
    let i = (s.floor() as usize).min(5);
    STOPS[i].lerp(STOPS[i + 1], s - i as f32)
}

/// shaders/shade.wgsl `shade_pixels` for one pixel: the packed RGBA8 colour.
pub fn shade_pixel(
    shade: &crate::layout::ShadeParams,
    primary: &Ray,
    hit: &gridrt_scene::Hit,
    stats: &gridrt_grid::RayStats,
    shadow_hit: &gridrt_scene::Hit,
    tri: [Vec3; 3],
) -> u32 {
    let view = View::from_code(shade.view).unwrap_or_default();
    let hmax = shade.heat_max;
    match view {
        View::HeatmapCells => return pack_rgba(heat(stats.cells as f32 / hmax)),
        View::HeatmapTests => return pack_rgba(heat(stats.tests as f32 / hmax)),
        _ => {}
    }
    if !hit.is_hit() {
        return pack_rgba(Vec3::new(0.08, 0.09, 0.12));
    }
    let [a, b, c] = tri;
    let mut n = normalize_scaled(normalize_scaled(b - a).cross(normalize_scaled(c - a)));
    let dir = normalize_scaled(primary.d());
    if n.dot(dir) > 0.0 {
        n = -n;
    }
    if view == View::Normals {
        return pack_rgba(n * 0.5 + 0.5);
    }
    if view == View::Depth {
        let dist = hit.t * primary.d().length();
        let x = (dist - shade.depth_near) / (shade.depth_far - shade.depth_near).max(f32::MIN_POSITIVE);
        return pack_rgba(Vec3::splat(1.0 - x.clamp(0.0, 1.0)));
    }
    let p = primary.at(hit.t);
    let light = Vec3::from(shade.light);
    let l = normalize_scaled(light - p);
    let lit = if shadow_hit.is_hit() { 0.0 } else { 1.0 };
    let head = n.dot(-dir).abs();
    let diffuse = n.dot(l).max(0.0) * lit;
    let base = Vec3::new(0.85, 0.8, 0.72);
    pack_rgba(base * (0.15 + 0.45 * head + 0.5 * diffuse))
}
