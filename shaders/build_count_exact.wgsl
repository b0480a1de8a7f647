// GPU grid build, phase 2 under exact insertion: how many triangles each cell holds, a cell
// counted when the triangle overlaps it (shared/overlap.wgsl), as the CPU's exact insertion
// counts it. One invocation per triangle.
//!include shared/build_exact.wgsl

@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;

@compute @workgroup_size(64)
fn build_count_exact(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let i = triangle_index(lid, wid);
    if i >= params.triangle_count {
        return;
    }
    let v = triangle_vertices(i);
    let r = cell_range(v, params);
    // A range of one cell is taken untested (as on the CPU).
    if all(r.lo == r.hi) {
        atomicAdd(&counts[linear_cell(r.lo, params.res)], 1u);
        return;
    }
    var t = exact_overlap_test(v, params);
    for (var z = r.lo.z; z <= r.hi.z; z++) {
        for (var y = r.lo.y; y <= r.hi.y; y++) {
            let run = overlap_row_run(&t, r.lo.x, r.hi.x, y, z);
            for (var x = run.x; x <= run.y; x++) {
                atomicAdd(&counts[linear_cell(vec3<u32>(x, y, z), params.res)], 1u);
            }
        }
    }
}
