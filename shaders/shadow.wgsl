// Shadow rays from the point light to each primary hit, stopping just short of it (t in
// [0, 1 - eps]); a miss marks a lit point. They all start at the light, so a tile's rays share
// their origin (tight packets) and an occluder near the light ends them early. Pixels without a
// hit get an empty ray (tmin > tmax), which the trace kernels skip.
// CPU port: crates/gpu/src/cpu.rs (`shadow_ray`).
//!include shared/render_bindings.wgsl

@group(0) @binding(0) var<uniform> shade: ShadeParams;
@group(0) @binding(1) var<storage, read> primary: array<Ray>;
@group(0) @binding(2) var<storage, read> primary_hits: array<Hit>;
@group(0) @binding(3) var<storage, read_write> shadow_rays: array<Ray>;

@compute @workgroup_size(64)
fn shadow_rays_from_hits(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= shade.pixel_count {
        return;
    }
    let h = primary_hits[i];
    if h.triangle == NO_HIT {
        shadow_rays[i] = Ray(vec4<f32>(0.0, 0.0, 0.0, 1.0), vec4<f32>(1.0, 0.0, 0.0, 0.0));
        return;
    }
    let p = hit_point(primary[i], h.t);
    // Stops short of the surface by a distance relative to the scene size.
    let from_light = p - shade.light;
    let eps = 1e-4 * shade.diagonal / max(length_scaled(from_light), MIN_POSITIVE_F32);
    shadow_rays[i] = Ray(vec4<f32>(shade.light, 0.0), vec4<f32>(from_light, 1.0 - eps));
}
