// The compact flat grid (Rust: crates/grid/src/flat.rs, `FlatGrid`): per 32 cells (linear cell
// index, x fastest) an occupancy word, the cells' bits and the rank of the word's first occupied
// cell among all occupied cells (`OccupancyWord { bits, rank }`); per occupied cell, in cell
// order, the start of its run of `refs` (`ref_start`, one more entry holding the total). An
// empty cell costs a bit test; the GPU holds the same arrays as the CPU.
@group(0) @binding(6) var<storage, read> ref_start: array<u32>;
@group(0) @binding(8) var<storage, read> occupied: array<vec2<u32>>;

// Whether cell `idx` holds references (FlatGrid::is_occupied).
fn is_occupied(idx: u32) -> bool {
    return ((occupied[idx >> 5u].x >> (idx & 31u)) & 1u) != 0u;
}

// The run refs[x .. y] of cell `idx`, which must be occupied (FlatGrid::refs_of): the word's
// rank plus the occupied cells before it in the word index `ref_start`.
fn refs_of(idx: u32) -> vec2<u32> {
    let w = occupied[idx >> 5u];
    let j = w.y + countOneBits(w.x & ((1u << (idx & 31u)) - 1u));
    return vec2<u32>(ref_start[j], ref_start[j + 1u]);
}
