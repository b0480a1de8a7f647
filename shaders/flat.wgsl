// Closest hit through a flat uniform grid (the compact layout of shared/flat_grid.wgsl).
// CPU port: crates/grid/src/trace/mod.rs (`trace_flat`).
//!include shared/closest_hit.wgsl
//!include shared/flat_grid.wgsl

// The flat grid's walk: every crossed cell in order (called by `trace` in shared/closest_hit.wgsl).
fn walk(g: GridRay) {
    var w = walker_init(g, params.res);
    loop {
        if !walker_next(&w) {
            return;
        }
        visit_cell();
        let idx = cell_index(w.out_cell, params.res);
        // FlatGrid::visit: an empty cell only checks the best hit so far.
        if is_occupied(idx) {
            let r = refs_of(idx);
            if test_cell(r.x, r.y, w.out_t_exit) {
                return;
            }
        } else if done_at(w.out_t_exit) {
            return;
        }
    }
}
