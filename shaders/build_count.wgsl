// GPU grid build, phase 2: how many triangles each cell holds (box insertion with the
// conservative margin, `cell_range`). One invocation per triangle.
//!include shared/build_triangles.wgsl

// One counter per cell (plus one unused: the scan's total goes there).
@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;

@compute @workgroup_size(64)
fn build_count(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let i = triangle_index(lid, wid);
    if i >= params.triangle_count {
        return;
    }
    let r = cell_range(triangle_vertices(i), params);
    for (var k = 0u; k < range_cells(r); k++) {
        atomicAdd(&counts[range_cell(r, k, params.res)], 1u);
    }
}
