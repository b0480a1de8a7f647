// GPU grid build, phase 2: how many triangles each cell holds (box insertion with the
// conservative margin, `cell_range`). One invocation per triangle.
//!include shared/types.wgsl
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;
// One counter per cell (plus one unused: the scan's total goes there).
@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;

@compute @workgroup_size(64)
fn build_count(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let i = group_index(wid, params.groups_x) * 64u + lid;
    if i >= params.triangle_count {
        return;
    }
    let r = cell_range(unpack_triangle(triangles[3u * i], triangles[3u * i + 1u], triangles[3u * i + 2u].x), params);
    for (var z = r.lo.z; z <= r.hi.z; z++) {
        for (var y = r.lo.y; y <= r.hi.y; y++) {
            let row = linear_cell(vec3<u32>(0u, y, z), params.res);
            for (var x = r.lo.x; x <= r.hi.x; x++) {
                atomicAdd(&counts[row + x], 1u);
            }
        }
    }
}
