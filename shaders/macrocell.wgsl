// Closest hit through macrocells over a flat grid: empty A^3 blocks are crossed in one step.
// CPU port: crates/grid/src/macrocell.rs (`MacrocellGrid::trace`).
//!include shared/trace_common.wgsl

@group(0) @binding(6) var<storage, read> cell_start: array<u32>;
// One bit per macrocell (x fastest). Mirrors MacrocellGrid::occupancy.
@group(0) @binding(7) var<storage, read> occupancy: array<u32>;

@compute @workgroup_size(64)
fn trace_macrocell(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= params.res.w {
        return;
    }
    var best = miss();
    var stats = RayStats(0u, 0u);
    let pr = prepare_ray(rays[i]);
    if pr.valid {
        let fine = grid_ray(pr);
        if !ray_is_empty(fine) {
            let res = params.res.xyz;
            let a = params.options.z;
            let af = f32(a);
            let macro_res = res / a;
            var mg = fine;
            mg.o = fine.o / af;
            mg.d = fine.d / af;
            mg.inv_d = fine.inv_d * af;
            var mw = walker_init(TRAVERSAL, mg, macro_res);
            var mailbox = empty_mailbox();
            let use_mailbox = params.options.y != 0u;
            var t_enter = fine.t0;
            var done = false;
            loop {
                if done || !walker_next(&mw) {
                    break;
                }
                stats.cells += 1u;
                let t_exit = mw.out_t_exit;
                let m = mw.out_cell;
                let mi = cell_index(m, macro_res);
                if (occupancy[mi / 32u] & (1u << (mi % 32u))) != 0u {
                    let lo = m * i32(a);
                    var sub = fine;
                    sub.o = fine.o - vec3<f32>(lo);
                    sub.t0 = t_enter;
                    sub.t1 = t_exit;
                    var fw = walker_init(TRAVERSAL, sub, vec3<u32>(a));
                    loop {
                        if !walker_next(&fw) {
                            break;
                        }
                        stats.cells += 1u;
                        let idx = cell_index(lo + fw.out_cell, res);
                        test_refs(pr, cell_start[idx], cell_start[idx + 1u], &best, &stats, &mailbox, use_mailbox);
                        if best.t < fw.out_t_exit {
                            done = true;
                            break;
                        }
                    }
                }
                if done || best.t < t_exit {
                    break;
                }
                t_enter = t_exit;
            }
        }
    }
    write_result(i, best, stats);
}
