// Closest hit through macrocells over a flat grid: empty A^3 blocks are crossed in one step (the
// last macrocell on an axis may be cut short by the grid's end).
// CPU port: crates/grid/src/macrocell.rs (`MacrocellGrid::trace`). The walk depends on the
// walker, as on the CPU: Amanatides-Woo walks the fine cells and crosses empty macrocells as
// blocks (shared/macrocell_aw.wgsl); the other walkers walk the macro grid and, in each occupied
// macrocell, its fine cells (shared/macrocell_nested.wgsl).
//!include shared/closest_hit.wgsl
//!include shared/flat_grid.wgsl
//!include shared/macrocell_{TRAVERSAL}.wgsl

// One bit per macrocell (x fastest). Mirrors MacrocellGrid::occupancy.
@group(0) @binding(7) var<storage, read> occupancy: array<u32>;

// The macro grid's resolution: macrocells of edge A from the origin, the last on an axis cut
// short where the fine resolution is not a multiple of A (macrocell::macro_resolution).
fn macro_resolution() -> vec3<u32> {
    return (params.res + vec3<u32>(params.macro_edge - 1u)) / params.macro_edge;
}

// Whether macrocell `m` holds no reference (MacrocellGrid::occupied).
fn macrocell_empty(m: vec3<i32>) -> bool {
    let mi = cell_index(m, macro_resolution());
    return (occupancy[mi / 32u] & (1u << (mi % 32u))) == 0u;
}
