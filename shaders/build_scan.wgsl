// GPU grid build, phase 3a: exclusive prefix sum of one block of SCAN_BLOCK elements per
// workgroup, in place: each invocation sums its run of SCAN_RUN consecutive elements, a
// Hillis–Steele scan of the 256 run sums in workgroup memory gives each run its offset, and the
// run is written back scanned. Each block's total goes to `block_sums` for the next level.
// Counts up to 2^31 references fit u32. Long runs keep the barriers few (each is costly on a
// CPU-emulated GPU).
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> block_sums: array<u32>;

const SCAN_THREADS: u32 = 256u;
const SCAN_RUN: u32 = 16u;
const SCAN_BLOCK: u32 = 4096u;
var<workgroup> sums: array<u32, 256>;

@compute @workgroup_size(256)
fn build_scan(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let block = group_index(wid, params.groups_x);
    let first = block * SCAN_BLOCK + lid * SCAN_RUN;
    let end = min(first + SCAN_RUN, params.count);
    var run = 0u;
    for (var i = first; i < end; i++) {
        run += data[i];
    }
    var s = run;
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
    var acc = s - run;
    for (var i = first; i < end; i++) {
        let x = data[i];
        data[i] = acc;
        acc += x;
    }
    if lid == SCAN_THREADS - 1u && block * SCAN_BLOCK < params.count {
        block_sums[block] = s;
    }
}
