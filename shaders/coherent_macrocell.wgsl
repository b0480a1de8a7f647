// Coherent packets through a macrocell grid: the packet kernel (shared/coherent.wgsl, entry
// point `trace_packets`) with empty macrocells of each box skipped whole; incoherent packets use
// macrocell.wgsl's `walk`. CPU port: crates/grid/src/coherent/mod.rs
// (`SliceCells for MacrocellGrid`).
//!include macrocell.wgsl
//!include shared/coherent.wgsl

// Steps through every cell in the box lo..=hi, testing the triangles of those within
// own_lo..=own_hi (this ray's own cells) against this invocation's ray, skipping
// the cells of empty macrocells.
fn test_box(lo: vec3<u32>, hi: vec3<u32>, own_lo: vec3<u32>, own_hi: vec3<u32>) {
    let use_mailbox = params.mailbox != 0u;
    let a = params.macro_edge;
    let macro_res = params.res / a;
    let mlo = lo / a;
    let mhi = hi / a;
    for (var mz = mlo.z; mz <= mhi.z; mz++) {
        for (var my = mlo.y; my <= mhi.y; my++) {
            for (var mx = mlo.x; mx <= mhi.x; mx++) {
                let m = vec3<u32>(mx, my, mz);
                let mi = m.x + macro_res.x * (m.y + macro_res.y * m.z);
                if (occupancy[mi / 32u] & (1u << (mi % 32u))) == 0u {
                    continue;
                }
                let blo = max(m * a, lo);
                let bhi = min(m * a + vec3<u32>(a - 1u), hi);
                for (var z = blo.z; z <= bhi.z; z++) {
                    for (var y = blo.y; y <= bhi.y; y++) {
                        let row = params.res.x * (y + params.res.y * z);
                        for (var x = blo.x; x <= bhi.x; x++) {
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
        }
    }
}
