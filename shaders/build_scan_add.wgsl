// GPU grid build, phase 3b: adds each block's offset (the scanned block sums of the next level)
// to its 512 elements, completing the exclusive prefix sum across blocks.
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read> block_offsets: array<u32>;

@compute @workgroup_size(256)
fn build_scan_add(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let block = group_index(wid, params.groups_x);
    let a = block * 512u + 2u * lid;
    if a >= params.count {
        return;
    }
    let add = block_offsets[block];
    data[a] += add;
    if a + 1u < params.count {
        data[a + 1u] += add;
    }
}
