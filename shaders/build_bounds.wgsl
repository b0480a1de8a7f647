// GPU grid build, phase 1: the scene's bounds. Each workgroup reduces its triangles' boxes in
// workgroup atomics, then folds them into six global atomics. Floats are compared through an
// order-preserving map to u32 (min and max are exact, so the bounds equal the CPU's).
//!include shared/types.wgsl
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;
// min.xyz, max.xyz as order keys (see `order_key`); cleared to (MAX, MAX, MAX, 0, 0, 0).
@group(0) @binding(2) var<storage, read_write> bounds: array<atomic<u32>, 6>;

var<workgroup> group_bounds: array<atomic<u32>, 6>;

// Monotone map of a float to u32: negative floats reversed below positive ones.
fn order_key(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

@compute @workgroup_size(64)
fn build_bounds(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    if lid < 3u {
        atomicStore(&group_bounds[lid], 0xFFFFFFFFu);
    } else if lid < 6u {
        atomicStore(&group_bounds[lid], 0u);
    }
    workgroupBarrier();
    let i = group_index(wid, params.groups_x) * 64u + lid;
    if i < params.triangle_count {
        let v = unpack_triangle(triangles[3u * i], triangles[3u * i + 1u], triangles[3u * i + 2u].x);
        let lo = min(min(v.a, v.b), v.c);
        let hi = max(max(v.a, v.b), v.c);
        atomicMin(&group_bounds[0], order_key(lo.x));
        atomicMin(&group_bounds[1], order_key(lo.y));
        atomicMin(&group_bounds[2], order_key(lo.z));
        atomicMax(&group_bounds[3], order_key(hi.x));
        atomicMax(&group_bounds[4], order_key(hi.y));
        atomicMax(&group_bounds[5], order_key(hi.z));
    }
    workgroupBarrier();
    if lid < 3u {
        atomicMin(&bounds[lid], atomicLoad(&group_bounds[lid]));
    } else if lid < 6u {
        atomicMax(&bounds[lid], atomicLoad(&group_bounds[lid]));
    }
}
