// Closest hit through a flat uniform grid (compact layout: cell_start + refs).
// CPU port: crates/grid/src/trace/mod.rs (`trace_flat`).
//!include shared/closest_hit.wgsl

// M + 1 offsets into `refs`. Mirrors FlatGrid::cell_start.
@group(0) @binding(6) var<storage, read> cell_start: array<u32>;

fn walk_flat(g: GridRay) {
    var w = walker_init(g, params.res);
    loop {
        if !walker_next(&w) {
            return;
        }
        visit_cell();
        let idx = cell_index(w.out_cell, params.res);
        if test_cell(cell_start[idx], cell_start[idx + 1u], w.out_t_exit) {
            return;
        }
    }
}

@compute @workgroup_size(64)
fn trace_flat(@builtin(global_invocation_id) gid: vec3<u32>) {
    if begin_ray(gid.x) {
        walk_flat(top_ray);
    }
    end_ray(gid.x);
}
