// GPU grid build, phase 4: every triangle writes its index into each of its cells' slots
// (`cursor` starts as `cell_start`; the order within a cell is settled by build_sort_cells).
//!include shared/build_triangles.wgsl

@group(0) @binding(2) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> refs: array<u32>;

@compute @workgroup_size(64)
fn build_scatter(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let i = triangle_index(lid, wid);
    if i >= params.triangle_count {
        return;
    }
    let r = cell_range(triangle_vertices(i), params);
    for (var k = 0u; k < range_cells(r); k++) {
        refs[atomicAdd(&cursor[range_cell(r, k, params.res)], 1u)] = i;
    }
}
