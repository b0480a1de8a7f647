// GPU grid build, phase 3a: exclusive prefix sum of one block of 512 elements per workgroup (two
// per invocation, a Hillis–Steele scan of the pair sums in workgroup memory), in place; each
// block's total goes to `block_sums` for the next level. Counts up to 2^31 references fit u32.
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> block_sums: array<u32>;

const SCAN_THREADS: u32 = 256u;
var<workgroup> sums: array<u32, 256>;

@compute @workgroup_size(256)
fn build_scan(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let block = group_index(wid, params.groups_x);
    let a = block * 2u * SCAN_THREADS + 2u * lid;
    var x0 = 0u;
    var x1 = 0u;
    if a < params.count {
        x0 = data[a];
    }
    if a + 1u < params.count {
        x1 = data[a + 1u];
    }
    var s = x0 + x1;
    sums[lid] = s;
    workgroupBarrier();
    for (var off = 1u; off < SCAN_THREADS; off <<= 1u) {
        var add = 0u;
        if lid >= off {
            add = sums[lid - off];
        }
        workgroupBarrier();
        s += add;
        sums[lid] = s;
        workgroupBarrier();
    }
    let before = s - x0 - x1;
    if a < params.count {
        data[a] = before;
    }
    if a + 1u < params.count {
        data[a + 1u] = before + x0;
    }
    if lid == SCAN_THREADS - 1u && block * 2u * SCAN_THREADS < params.count {
        block_sums[block] = s;
    }
}
