// Closest hit through a flat uniform grid (cell_start + refs, and a bit per cell).
// CPU port: crates/grid/src/trace/mod.rs (`trace_flat`).
//!include shared/closest_hit.wgsl
//!include shared/occupied.wgsl

// M + 1 offsets into `refs`. Mirrors FlatGrid::cell_start.
@group(0) @binding(6) var<storage, read> cell_start: array<u32>;

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
            if test_cell(cell_start[idx], cell_start[idx + 1u], w.out_t_exit) {
                return;
            }
        } else if done_at(w.out_t_exit) {
            return;
        }
    }
}
