// GPU grid build, phase 7: the compact flat grid (shared/flat_grid.wgsl) from the cell table:
// each word gets its rank (the scanned counts of build_cell_bits) and writes the starts of its
// occupied cells to ref_start from that rank on; the last word also writes the total. One
// invocation per word. CPU port: FlatGrid::new (crates/grid/src/flat.rs).
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read> cell_start: array<u32>;
@group(0) @binding(2) var<storage, read_write> occupied: array<vec2<u32>>;
// Each word's rank (exclusive prefix sum of its occupied cells); the element after the last
// word holds the number of occupied cells.
@group(0) @binding(3) var<storage, read> ranks: array<u32>;
@group(0) @binding(4) var<storage, read_write> ref_start: array<u32>;

@compute @workgroup_size(64)
fn build_compact(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let k = group_index(wid, params.groups_x) * 64u + lid;
    let words = (params.count + 31u) / 32u;
    if k >= words {
        return;
    }
    let rank = ranks[k];
    var bits = occupied[k].x;
    occupied[k] = vec2<u32>(bits, rank);
    var o = rank;
    while bits != 0u {
        ref_start[o] = cell_start[32u * k + countTrailingZeros(bits)];
        o += 1u;
        bits &= bits - 1u;
    }
    if k == words - 1u {
        ref_start[ranks[words]] = cell_start[params.count];
    }
}
