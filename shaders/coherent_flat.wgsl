// Coherent packets through a flat uniform grid: the packet kernel (shared/coherent.wgsl, entry
// point `trace_packets`) with the flat grid's box of cells; incoherent packets use flat.wgsl's
// `walk`. CPU port: crates/grid/src/coherent/mod.rs (`SliceCells for FlatGrid`).
//!include flat.wgsl
//!include shared/coherent.wgsl

// Steps through every cell in the box lo..=hi, testing the triangles of those within
// own_lo..=own_hi (this ray's own cells) against this invocation's ray.
fn test_box(lo: vec3<u32>, hi: vec3<u32>, own_lo: vec3<u32>, own_hi: vec3<u32>) {
    let use_mailbox = params.mailbox != 0u;
    for (var z = lo.z; z <= hi.z; z++) {
        for (var y = lo.y; y <= hi.y; y++) {
            let row = params.res.x * (y + params.res.y * z);
            for (var x = lo.x; x <= hi.x; x++) {
                let c = vec3<u32>(x, y, z);
                if any(c < own_lo) || any(c > own_hi) {
                    continue;
                }
                visit_cell();
                let idx = row + x;
                for (var k = cell_start[idx]; k < cell_start[idx + 1u]; k++) {
                    test_triangle(refs[k], use_mailbox);
                }
            }
        }
    }
}
