//!include shared/trace_common.wgsl
// Closest hit through a hierarchy of grids (multi-resolution and two-level grids share the
// layout): a stack of walkers, one per level.
// CPU port: crates/grid/src/hierarchy.rs (`Hierarchy::trace`).

// Mirrors GpuNode: xyz = resolution, w = index of the node's first cell.
struct Node {
    res_first: vec4<u32>,
}

// [start, count] of a leaf, or [child node, CHILD]. Mirrors Hierarchy::cells.
@group(0) @binding(6) var<storage, read> cells: array<vec2<u32>>;
@group(0) @binding(7) var<storage, read> nodes: array<Node>;

const CHILD: u32 = 0xffffffffu;
const MAX_DEPTH: u32 = 8u;

fn trace_hierarchy(i: u32) {
    var best = miss();
    var stats = RayStats(0u, 0u);
    let pr = prepare_ray(rays[i]);
    if pr.valid {
        let top = grid_ray(pr);
        if !ray_is_empty(top) {
            // Parents of the current level; the current walker lives in `w` (copied only on
            // descent and return: naga's SPIR-V backend cannot pass `&stack[f]` to a function).
            var stack: array<Walker, 8>;
            var frame_node: array<u32, 8>;
            var frame_t_enter: array<f32, 8>;
            var mailbox = empty_mailbox();
            let use_mailbox = params.options.y != 0u;
            let kind = TRAVERSAL;
            var w = walker_init(kind, top, nodes[0].res_first.xyz);
            var node_idx = 0u;
            var t_enter = top.t0;
            var depth = 0u;
            loop {
                if !walker_next(&w) {
                    if depth == 0u {
                        break;
                    }
                    depth -= 1u;
                    w = stack[depth];
                    node_idx = frame_node[depth];
                    t_enter = frame_t_enter[depth];
                    continue;
                }
                stats.cells += 1u;
                let node = nodes[node_idx];
                let c = w.out_cell;
                let t_exit = w.out_t_exit;
                let cell = cells[node.res_first.w + cell_index(c, node.res_first.xyz)];
                let te = t_enter;
                t_enter = t_exit;
                if cell.y == CHILD {
                    if depth + 1u < MAX_DEPTH {
                        stack[depth] = w;
                        frame_node[depth] = node_idx;
                        frame_t_enter[depth] = t_enter;
                        depth += 1u;
                        let child_res = nodes[cell.x].res_first.xyz;
                        let r = child_ray(w.g, c, child_res, te, t_exit);
                        w = walker_init(kind, r, child_res);
                        node_idx = cell.x;
                        t_enter = r.t0;
                    }
                    continue;
                }
                test_refs(pr, cell.x, cell.x + cell.y, &best, &stats, &mailbox, use_mailbox);
                if best.t < t_exit {
                    break;
                }
            }
        }
    }
    write_result(i, best, stats);
}
