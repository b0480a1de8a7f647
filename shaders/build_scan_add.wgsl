// GPU grid build, phase 3b: adds each block's offset (the scanned block sums of the next level)
// to its 4096 elements (build_scan's SCAN_BLOCK), completing the exclusive prefix sum across
// blocks.
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read> block_offsets: array<u32>;

const ADD_BLOCK: u32 = 4096u;
const ADD_RUN: u32 = 16u;

@compute @workgroup_size(256)
fn build_scan_add(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let block = group_index(wid, params.groups_x);
    let first = block * ADD_BLOCK + lid * ADD_RUN;
    let end = min(first + ADD_RUN, params.count);
    let add = block_offsets[block];
    for (var i = first; i < end; i++) {
        data[i] += add;
    }
}
