// The flat grid's occupancy: one bit per cell (linear cell index, x fastest, 32 to a word), set
// when the cell holds a reference. The bits of gridrt_grid::OccupancyWord, and
// `is_occupied` is FlatGrid::is_occupied: an empty cell costs a read of this small array, not
// two reads of the M + 1 offsets.
@group(0) @binding(8) var<storage, read> occupied: array<u32>;

fn is_occupied(idx: u32) -> bool {
    return ((occupied[idx >> 5u] >> (idx & 31u)) & 1u) != 0u;
}
