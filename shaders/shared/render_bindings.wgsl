//!include shared/ray.wgsl
// Render-pass data. Keep in sync with crates/gpu/src/layout.rs (GpuCamera, ShadeParams).

struct Camera {
    // xyz: eye; w: tan(vfov / 2).
    eye: vec4<f32>,
    // xyz: right (unit); w: width.
    right: vec4<f32>,
    // xyz: up (unit); w: height.
    up: vec4<f32>,
    // xyz: forward (unit); w: aspect (width / height).
    forward: vec4<f32>,
}

struct ShadeParams {
    // xyz: point light; w: scene diagonal.
    light: vec4<f32>,
    // x: view (0 shaded, 1 normals, 2 depth, 3 heatmap-cells, 4 heatmap-tests);
    // y: heatmap maximum (f32 bits); z: width; w: height.
    view: vec4<u32>,
    // x, y: depth near / far.
    depth: vec4<f32>,
    // x: first pixel of this dispatch (a tile of the frame); y: pixels in it. The per-pixel
    // buffers are bound from the tile's first pixel, so kernels index them from 0.
    tile: vec4<u32>,
}

// The primary ray of pixel (x, y), row 0 at the top. CPU port: crates/gpu/src/cpu.rs.
fn camera_ray(cam: Camera, x: u32, y: u32) -> Ray {
    let w = cam.right.w;
    let h = cam.up.w;
    let half_v = cam.eye.w;
    let half_h = half_v * cam.forward.w;
    let sx = ((f32(x) + 0.5) / w * 2.0 - 1.0) * half_h;
    let sy = (1.0 - (f32(y) + 0.5) / h * 2.0) * half_v;
    let d = cam.forward.xyz + cam.right.xyz * sx + cam.up.xyz * sy;
    return Ray(vec4<f32>(cam.eye.xyz, 0.0), vec4<f32>(d, inf()));
}

// The point at parameter t along r.
fn hit_point(r: Ray, t: f32) -> vec3<f32> {
    return r.origin_tmin.xyz + r.dir_tmax.xyz * t;
}
