// Closest hit through macrocells over a flat grid: empty A^3 blocks are crossed in one step.
// CPU port: crates/grid/src/macrocell.rs (`MacrocellGrid::trace`). The walk depends on the
// walker, as on the CPU: Amanatides-Woo walks the fine cells and crosses empty macrocells as
// blocks (shared/macrocell_aw.wgsl); the other walkers walk the macro grid and, in each occupied
// macrocell, its fine cells (shared/macrocell_nested.wgsl).
//!include shared/closest_hit.wgsl
//!include shared/flat_grid.wgsl
//!include shared/macrocell_{TRAVERSAL}.wgsl

// One bit per macrocell (x fastest). Mirrors MacrocellGrid::occupancy.
@group(0) @binding(7) var<storage, read> occupancy: array<u32>;

// Whether macrocell `m` holds no reference (MacrocellGrid::occupied).
fn macrocell_empty(m: vec3<i32>) -> bool {
    let macro_res = params.res / params.macro_edge;
    let mi = cell_index(m, macro_res);
    return (occupancy[mi / 32u] & (1u << (mi % 32u))) == 0u;
}
