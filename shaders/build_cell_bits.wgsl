// GPU grid build, phase 6: the occupancy word of every 32 cells from the cell table (bit j: cell
// 32k + j holds references) and its count of occupied cells, whose exclusive prefix sum
// (build_scan.wgsl) is each word's rank. One invocation per word. CPU port: the occupancy bits
// of FlatGrid::new (crates/grid/src/flat.rs).
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read> cell_start: array<u32>;
// (bits, rank): build_compact writes the rank.
@group(0) @binding(2) var<storage, read_write> occupied: array<vec2<u32>>;
// Occupied cells per word; one more element, left 0, becomes the total when scanned.
@group(0) @binding(3) var<storage, read_write> word_counts: array<u32>;

@compute @workgroup_size(64)
fn build_cell_bits(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let k = group_index(wid, params.groups_x) * 64u + lid;
    // params.count: the number of cells.
    let first = 32u * k;
    if first >= params.count {
        return;
    }
    let n = min(32u, params.count - first);
    var bits = 0u;
    var prev = cell_start[first];
    for (var j = 0u; j < n; j++) {
        let next = cell_start[first + j + 1u];
        bits |= select(0u, 1u << j, next > prev);
        prev = next;
    }
    occupied[k] = vec2<u32>(bits, 0u);
    word_counts[k] = countOneBits(bits);
}
