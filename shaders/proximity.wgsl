// Closest hit through a flat grid with proximity clouds: from an empty cell at chessboard
// distance k >= MIN_JUMP_DISTANCE from any triangle, jump out of the empty cube around it.
// CPU port: crates/grid/src/proximity.rs (`ProximityGrid::trace`).
//!include shared/closest_hit.wgsl
//!include shared/flat_grid.wgsl

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

// Smallest distance at which the walk jumps out of the empty cube around its cell (a restart costs
// several steps). Rust: proximity::MIN_JUMP_DISTANCE.
const MIN_JUMP_DISTANCE: i32 = 4;

// The flat grid's walk, restarted beyond the empty cube around a cell at distance
// k >= MIN_JUMP_DISTANCE (called by `trace` in shared/closest_hit.wgsl).
fn walk(g_in: GridRay) {
    var g = g_in;
    let resi = vec3<i32>(params.res);
    var w = walker_init(g, params.res);
    loop {
        if !walker_next(&w) {
            return;
        }
        visit_cell();
        let c = w.out_cell;
        let idx = cell_index(c, params.res);
        let k = i32((distance[idx / 4u] >> (8u * (idx % 4u))) & 0xffu);
        if k >= MIN_JUMP_DISTANCE {
            let lo = max(c - vec3<i32>(k - 1), vec3<i32>(0));
            let hi = min(c + vec3<i32>(k), resi);
            let t = min(exit_of_box(g, lo, hi), g.t1);
            if t > g.t0 && t < g.t1 {
                g.t0 = t;
                w = walker_init(g, params.res);
                continue;
            }
            if t >= g.t1 {
                return;
            }
        }
        // Distance 0: an occupied cell.
        if k == 0 {
            let r = refs_of(idx);
            if test_cell(r.x, r.y, w.out_t_exit) {
                return;
            }
        } else if done_at(w.out_t_exit) {
            return;
        }
    }
}
