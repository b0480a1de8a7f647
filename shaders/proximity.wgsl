// Closest hit through a flat grid with proximity clouds: from an empty cell at chessboard
// distance k >= 2 from any triangle, jump out of the empty cube around it.
// CPU port: crates/grid/src/proximity.rs (`ProximityGrid::trace`).
//!include shared/trace_common.wgsl

@group(0) @binding(6) var<storage, read> cell_start: array<u32>;
// Distance per cell, one byte each, four to a word. Mirrors ProximityGrid::distance.
@group(0) @binding(7) var<storage, read> distance: array<u32>;

fn exit_of_box(g: GridRay, lo: vec3<i32>, hi: vec3<i32>) -> f32 {
    var t = inf();
    for (var a = 0u; a < 3u; a++) {
        if g.d[a] != 0.0 {
            let plane = f32(select(lo[a], hi[a], g.d[a] > 0.0));
            t = min(t, (plane - g.o[a]) * g.inv_d[a]);
        }
    }
    return t;
}

@compute @workgroup_size(64)
fn trace_proximity(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= params.res.w {
        return;
    }
    var best = miss();
    var stats = RayStats(0u, 0u);
    let pr = prepare_ray(rays[i]);
    if pr.valid {
        var g = grid_ray(pr);
        if !ray_is_empty(g) {
            let res = params.res.xyz;
            let resi = vec3<i32>(res);
            var w = walker_init(TRAVERSAL, g, res);
            var mailbox = empty_mailbox();
            let use_mailbox = params.options.y != 0u;
            loop {
                if !walker_next(&w) {
                    break;
                }
                stats.cells += 1u;
                let c = w.out_cell;
                let idx = cell_index(c, res);
                let k = i32((distance[idx / 4u] >> (8u * (idx % 4u))) & 0xffu);
                if k >= 2 {
                    let lo = max(c - vec3<i32>(k - 1), vec3<i32>(0));
                    let hi = min(c + vec3<i32>(k), resi);
                    let t = min(exit_of_box(g, lo, hi), g.t1);
                    if t > g.t0 && t < g.t1 {
                        g.t0 = t;
                        w = walker_init(TRAVERSAL, g, res);
                        continue;
                    }
                    if t >= g.t1 {
                        break;
                    }
                }
                test_refs(pr, cell_start[idx], cell_start[idx + 1u], &best, &stats, &mailbox, use_mailbox);
                if best.t < w.out_t_exit {
                    break;
                }
            }
        }
    }
    write_result(i, best, stats);
}
