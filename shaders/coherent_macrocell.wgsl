// Coherent packets through a macrocell grid: the packet kernel (shared/coherent.wgsl, entry
// point `trace_packets`) with empty macrocells of each box skipped whole; incoherent packets use
// macrocell.wgsl's `walk`. CPU port: crates/grid/src/coherent/mod.rs
// (`SliceCells for MacrocellGrid`).
//!include macrocell.wgsl
//!include shared/coherent.wgsl

// Tests the triangles of the box lo..=hi's cells that are this ray's own (own_lo..=own_hi),
// skipping empty macrocells.
fn test_box(lo: vec3<u32>, hi: vec3<u32>, own_lo: vec3<u32>, own_hi: vec3<u32>) {
    let a = params.macro_edge;
    let mlo = max(lo, own_lo) / a;
    let mhi = min(hi, own_hi) / a;
    for (var mz = mlo.z; mz <= mhi.z; mz++) {
        for (var my = mlo.y; my <= mhi.y; my++) {
            for (var mx = mlo.x; mx <= mhi.x; mx++) {
                let m = vec3<u32>(mx, my, mz);
                if !macrocell_empty(vec3<i32>(m)) {
                    test_cells(max(m * a, lo), min(m * a + vec3<u32>(a - 1u), hi), own_lo, own_hi);
                }
            }
        }
    }
}
