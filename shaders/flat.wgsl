// Closest hit through a flat uniform grid (compact layout: cell_start + refs).
// CPU port: crates/grid/src/trace.rs (`trace_flat`).
//!include shared/trace_common.wgsl

// M + 1 offsets into `refs`. Mirrors FlatGrid::cell_start.
@group(0) @binding(6) var<storage, read> cell_start: array<u32>;

@compute @workgroup_size(64)
fn trace_flat(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= params.res.w {
        return;
    }
    var best = miss();
    var stats = RayStats(0u, 0u);
    let pr = prepare_ray(rays[i]);
    if pr.valid {
        let g = grid_ray(pr);
        if !ray_is_empty(g) {
            let res = params.res.xyz;
            var w = walker_init(TRAVERSAL, g, res);
            var mailbox = empty_mailbox();
            let use_mailbox = params.options.y != 0u;
            loop {
                if !walker_next(&w) {
                    break;
                }
                stats.cells += 1u;
                let idx = cell_index(w.out_cell, res);
                test_refs(pr, cell_start[idx], cell_start[idx + 1u], &best, &stats, &mailbox, use_mailbox);
                if best.t < w.out_t_exit {
                    break;
                }
            }
        }
    }
    write_result(i, best, stats);
}
