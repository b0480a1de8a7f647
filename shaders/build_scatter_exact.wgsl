// GPU grid build, phase 4 under exact insertion: every triangle writes its index into the slots
// of the cells build_count_exact counted for it (the same runs; the order within a cell is
// settled by build_sort_cells).
//!include shared/build_exact.wgsl

@group(0) @binding(2) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> refs: array<u32>;

@compute @workgroup_size(64)
fn build_scatter_exact(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let i = triangle_index(lid, wid);
    if i >= params.triangle_count {
        return;
    }
    let v = triangle_vertices(i);
    let r = cell_range(v, params);
    if all(r.lo == r.hi) {
        refs[atomicAdd(&cursor[linear_cell(r.lo, params.res)], 1u)] = i;
        return;
    }
    var t = exact_overlap_test(v, params);
    for (var z = r.lo.z; z <= r.hi.z; z++) {
        for (var y = r.lo.y; y <= r.hi.y; y++) {
            let run = overlap_row_run(&t, r.lo.x, r.hi.x, y, z);
            for (var x = run.x; x <= run.y; x++) {
                refs[atomicAdd(&cursor[linear_cell(vec3<u32>(x, y, z), params.res)], 1u)] = i;
            }
        }
    }
}
