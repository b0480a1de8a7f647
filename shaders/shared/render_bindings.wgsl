//!include shared/ray.wgsl
// Render-pass data. Keep in sync with crates/gpu/src/layout.rs (GpuCamera, ShadeParams).

// Rust: crates/gpu/src/layout.rs `GpuCamera` (field by field).
struct Camera {
    eye: vec3<f32>,
    tan_half_vfov: f32,
    right: vec3<f32>,
    width: f32,
    up: vec3<f32>,
    height: f32,
    forward: vec3<f32>,
    aspect: f32,
}

// Rust: crates/gpu/src/layout.rs `ShadeParams` (field by field).
struct ShadeParams {
    light: vec3<f32>,
    diagonal: f32,
    // View code (crates/gpu/src/view.rs): 0 shaded, 1 normals, 2 depth, 3 heatmap-cells,
    // 4 heatmap-tests.
    view: u32,
    heat_max: f32,
    width: u32,
    height: u32,
    depth_near: f32,
    depth_far: f32,
    // The tile: the per-pixel buffers are bound from its first pixel (kernels index from 0).
    first_pixel: u32,
    pixel_count: u32,
}

// The primary ray of pixel (x, y), row 0 at the top. CPU port: crates/gpu/src/cpu.rs.
fn camera_ray(cam: Camera, x: u32, y: u32) -> Ray {
    let w = cam.width;
    let h = cam.height;
    let half_v = cam.tan_half_vfov;
    let half_h = half_v * cam.aspect;
    let sx = ((f32(x) + 0.5) / w * 2.0 - 1.0) * half_h;
    let sy = (1.0 - (f32(y) + 0.5) / h * 2.0) * half_v;
    let d = cam.forward + cam.right * sx + cam.up * sy;
    return Ray(vec4<f32>(cam.eye, 0.0), vec4<f32>(d, inf()));
}

// A vector's length and direction at any scene scale (its squared length would leave f32 beyond
// about 1.8e19 or below 1e-19 per component): divided by its largest component first. A zero
// vector has no direction. CPU twins: crates/scene/src/scaled.rs.
fn length_scaled(v: vec3<f32>) -> f32 {
    let m = max(max(abs(v.x), abs(v.y)), abs(v.z));
    if m > 0.0 {
        return m * length(v / m);
    }
    return m;
}

fn normalize_scaled(v: vec3<f32>) -> vec3<f32> {
    let m = max(max(abs(v.x), abs(v.y)), abs(v.z));
    if m > 0.0 {
        return normalize(v / m);
    }
    return vec3<f32>(0.0);
}

// The smallest normal f32.
const MIN_POSITIVE_F32: f32 = 1.17549435e-38;

// The point at parameter t along r.
fn hit_point(r: Ray, t: f32) -> vec3<f32> {
    return r.origin_tmin.xyz + r.dir_tmax.xyz * t;
}
