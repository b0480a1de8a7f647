// Primary rays of a pinhole camera, one per pixel, row-major from the top-left.
// CPU port: crates/gpu/src/cpu.rs (`camera_ray`).
//!include shared/render_bindings.wgsl

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read_write> out_rays: array<Ray>;
@group(0) @binding(2) var<uniform> shade: ShadeParams;

@compute @workgroup_size(64)
fn camera_rays(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = u32(camera.width);
    if gid.x >= shade.pixel_count {
        return;
    }
    let p = shade.first_pixel + gid.x;
    out_rays[gid.x] = camera_ray(camera, p % w, p / w);
}
