// Final colour per pixel for the five views: shaded (headlight diffuse + shadow from a point
// light), normals, depth, heatmap of cells visited, heatmap of triangle tests.
// Output: RGBA8 packed in a u32 per pixel. CPU port: crates/gpu/src/cpu.rs (`shade_pixel`, `heat`).
//!include shared/render_bindings.wgsl

@group(0) @binding(0) var<uniform> shade: ShadeParams;
@group(0) @binding(1) var<storage, read> primary: array<Ray>;
@group(0) @binding(2) var<storage, read> primary_hits: array<Hit>;
@group(0) @binding(3) var<storage, read> primary_stats: array<RayStats>;
@group(0) @binding(4) var<storage, read> shadow_hits: array<Hit>;
@group(0) @binding(5) var<storage, read> verts: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> pixels: array<u32>;

fn pack_rgba(c: vec3<f32>) -> u32 {
    let q = vec3<u32>(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)) * 255.0 + 0.5);
    return q.x | (q.y << 8u) | (q.z << 16u) | (255u << 24u);
}

// Heatmap colour scale: black -> blue -> cyan -> green -> yellow -> red -> white at x = 1.
fn heat(x: f32) -> vec3<f32> {
    let s = clamp(x, 0.0, 1.0) * 6.0;
    let stops = array<vec3<f32>, 7>(
        vec3<f32>(0.0, 0.0, 0.0), vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0, 1.0, 1.0),
        vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0),
        vec3<f32>(1.0, 1.0, 1.0));
    let i = min(u32(floor(s)), 5u);
    return mix(stops[i], stops[i + 1u], s - f32(i));
}

@compute @workgroup_size(64)
fn shade_pixels(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= shade.pixel_count {
        return;
    }
    let view = shade.view;
    let h = primary_hits[i];
    let st = primary_stats[i];
    let hmax = shade.heat_max;
    if view == 3u {
        pixels[i] = pack_rgba(heat(f32(st.cells) / hmax));
        return;
    }
    if view == 4u {
        pixels[i] = pack_rgba(heat(f32(st.tests) / hmax));
        return;
    }
    if h.triangle == NO_HIT {
        pixels[i] = pack_rgba(vec3<f32>(0.08, 0.09, 0.12));
        return;
    }
    let r = primary[i];
    let vs = unpack_triangle(verts[3u * h.triangle], verts[3u * h.triangle + 1u], verts[3u * h.triangle + 2u].x);
    let a = vs.a;
    let b = vs.b;
    let c = vs.c;
    var n = normalize_scaled(cross(normalize_scaled(b - a), normalize_scaled(c - a)));
    let dir = normalize_scaled(r.dir_tmax.xyz);
    if dot(n, dir) > 0.0 {
        n = -n;
    }
    if view == 1u {
        pixels[i] = pack_rgba(n * 0.5 + 0.5);
        return;
    }
    if view == 2u {
        let dist = h.t * length(r.dir_tmax.xyz);
        let x = (dist - shade.depth_near) / max(shade.depth_far - shade.depth_near, MIN_POSITIVE_F32);
        pixels[i] = pack_rgba(vec3<f32>(1.0 - clamp(x, 0.0, 1.0)));
        return;
    }
    let p = hit_point(r, h.t);
    let l = normalize_scaled(shade.light - p);
    let lit = select(0.0, 1.0, shadow_hits[i].triangle == NO_HIT);
    let head = abs(dot(n, -dir));
    let diffuse = max(dot(n, l), 0.0) * lit;
    let base = vec3<f32>(0.85, 0.8, 0.72);
    pixels[i] = pack_rgba(base * (0.15 + 0.45 * head + 0.5 * diffuse));
}
