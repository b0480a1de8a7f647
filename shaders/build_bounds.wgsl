// GPU grid build, phase 1: the scene's bounds, folded into six global atomics through an
// order-preserving map of floats to u32 (min and max are exact, so the bounds equal the CPU's;
// the ±3e38 start values lose to any vertex, which the loader keeps within 1e30).
//!include shared/build_triangles.wgsl

// min.xyz, max.xyz as order keys (see `order_key`); cleared to (MAX, MAX, MAX, 0, 0, 0).
@group(0) @binding(2) var<storage, read_write> bounds: array<atomic<u32>, 6>;

var<workgroup> group_lo: array<vec3<f32>, 64>;
var<workgroup> group_hi: array<vec3<f32>, 64>;

// Monotone map of a float to u32: negative floats reversed below positive ones.
fn order_key(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

// Each invocation folds every (groups × 64)-th triangle, the workgroup reduces its 64 boxes in
// workgroup memory, and one invocation folds the result into the global atomics.
@compute @workgroup_size(64)
fn build_bounds(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    var lo = vec3<f32>(3.0e38);
    var hi = vec3<f32>(-3.0e38);
    let stride = groups.x * groups.y * 64u;
    for (var i = triangle_index(lid, wid); i < params.triangle_count; i += stride) {
        let v = triangle_vertices(i);
        lo = min(lo, min(min(v.a, v.b), v.c));
        hi = max(hi, max(max(v.a, v.b), v.c));
    }
    group_lo[lid] = lo;
    group_hi[lid] = hi;
    workgroupBarrier();
    for (var half = 32u; half > 0u; half >>= 1u) {
        if lid < half {
            group_lo[lid] = min(group_lo[lid], group_lo[lid + half]);
            group_hi[lid] = max(group_hi[lid], group_hi[lid + half]);
        }
        workgroupBarrier();
    }
    if lid == 0u {
        let l = group_lo[0];
        let h = group_hi[0];
        atomicMin(&bounds[0], order_key(l.x));
        atomicMin(&bounds[1], order_key(l.y));
        atomicMin(&bounds[2], order_key(l.z));
        atomicMax(&bounds[3], order_key(h.x));
        atomicMax(&bounds[4], order_key(h.y));
        atomicMax(&bounds[5], order_key(h.z));
    }
}
