// GPU grid build, phases 2 and 4 under exact insertion: each triangle's cells, a cell taken when
// the triangle overlaps it (shared/overlap.wgsl, the CPU's test), counted (params.scatter = 0:
// `cells` are the counts) or given the triangle's index (1: `cells` are the cursors, starting
// as cell_start; the order within a cell is settled by build_sort_cells). One entry point for
// both passes: the overlap test is long, and a software adapter compiles each pipeline apart.
// One invocation per triangle.
//!include shared/build_exact.wgsl

@group(0) @binding(2) var<storage, read_write> cells: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> refs: array<u32>;

fn insert_exact(cell: u32, i: u32) {
    let slot = atomicAdd(&cells[cell], 1u);
    if params.scatter != 0u {
        refs[slot] = i;
    }
}

@compute @workgroup_size(64)
fn build_insert_exact(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let i = triangle_index(lid, wid);
    if i >= params.triangle_count {
        return;
    }
    let v = triangle_vertices(i);
    let r = cell_range(v, params);
    // A range of one cell is taken untested (as on the CPU).
    if all(r.lo == r.hi) {
        insert_exact(linear_cell(r.lo, params.res), i);
        return;
    }
    var t = exact_overlap_test(v, params);
    for (var z = r.lo.z; z <= r.hi.z; z++) {
        for (var y = r.lo.y; y <= r.hi.y; y++) {
            let run = overlap_row_run(&t, r.lo.x, r.hi.x, y, z);
            for (var x = run.x; x <= run.y; x++) {
                insert_exact(linear_cell(vec3<u32>(x, y, z), params.res), i);
            }
        }
    }
}
