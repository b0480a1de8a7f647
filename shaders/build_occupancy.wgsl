// GPU grid build, macrocells: from the fine grid's occupancy words (shared/flat_grid.wgsl), one
// bit per macrocell of edge A (`params.macro_edge`) that holds a reference, x fastest, 32 to a
// word (the layout of gridrt_grid::macrocell). One invocation per fine cell; `occupancy` starts
// cleared.
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read> occupied: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read_write> occupancy: array<atomic<u32>>;

@compute @workgroup_size(64)
fn build_occupancy(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let i = group_index(wid, params.groups_x) * 64u + lid;
    if i >= params.count || ((occupied[i >> 5u].x >> (i & 31u)) & 1u) == 0u {
        return;
    }
    let res = params.res;
    let c = vec3<u32>(i % res.x, (i / res.x) % res.y, i / (res.x * res.y));
    let a = params.macro_edge;
    let m = linear_cell(c / a, (res + vec3<u32>(a - 1u)) / a);
    atomicOr(&occupancy[m / 32u], 1u << (m % 32u));
}
