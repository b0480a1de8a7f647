// GPU grid build, phase 5: each cell's references in increasing triangle order, as the CPU
// build leaves them (so the two grids are bit-identical). Per cell: nothing for one already in
// order, insertion sort for short cells, heapsort (in place, O(n log n)) for
// long ones.
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read> cell_start: array<u32>;
@group(0) @binding(2) var<storage, read_write> refs: array<u32>;

const INSERTION_MAX: u32 = 128u;
// Cells per invocation (the host dispatches cells / (64 × SORT_RUN) workgroups).
const SORT_RUN: u32 = 16u;

// Restores the max-heap over refs[s .. s + end] (inclusive) below `root`.
fn sift_down(s: u32, first: u32, end: u32) {
    var root = first;
    loop {
        let child = 2u * root + 1u;
        if child > end {
            break;
        }
        var top = root;
        if refs[s + top] < refs[s + child] {
            top = child;
        }
        if child + 1u <= end && refs[s + top] < refs[s + child + 1u] {
            top = child + 1u;
        }
        if top == root {
            break;
        }
        let t = refs[s + root];
        refs[s + root] = refs[s + top];
        refs[s + top] = t;
        root = top;
    }
}

// Sorts the references of cell `c`.
fn sort_cell(c: u32) {
    let s = cell_start[c];
    let n = cell_start[c + 1u] - s;
    if n < 2u {
        return;
    }
    // The scatter's order is often already increasing (invocations run roughly in order).
    var sorted = true;
    for (var i = 1u; i < n && sorted; i++) {
        sorted = refs[s + i - 1u] < refs[s + i];
    }
    if sorted {
        return;
    }
    if n <= INSERTION_MAX {
        for (var i = 1u; i < n; i++) {
            let v = refs[s + i];
            var j = i;
            while j > 0u && refs[s + j - 1u] > v {
                refs[s + j] = refs[s + j - 1u];
                j -= 1u;
            }
            refs[s + j] = v;
        }
        return;
    }
    for (var k = n / 2u; k > 0u; k--) {
        sift_down(s, k - 1u, n - 1u);
    }
    for (var end = n - 1u; end > 0u; end--) {
        let t = refs[s];
        refs[s] = refs[s + end];
        refs[s + end] = t;
        sift_down(s, 0u, end - 1u);
    }
}

// Each invocation sorts a run of SORT_RUN consecutive cells (few invocations: most cells are
// empty, and each invocation has a fixed cost on a CPU-emulated GPU).
@compute @workgroup_size(64)
fn build_sort_cells(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>) {
    let first = (group_index(wid, params.groups_x) * 64u + lid) * SORT_RUN;
    let end = min(first + SORT_RUN, params.count);
    for (var c = first; c < end; c++) {
        sort_cell(c);
    }
}
