// Coherent packets through a flat uniform grid: the packet kernel (shared/coherent.wgsl, entry
// point `trace_packets`) with the flat grid's box of cells; incoherent packets use flat.wgsl's
// `walk`. CPU port: crates/grid/src/coherent/mod.rs (`SliceCells for FlatGrid`).
//!include flat.wgsl
//!include shared/coherent.wgsl

// Tests the triangles of the box lo..=hi's cells that are this ray's own (own_lo..=own_hi).
fn test_box(lo: vec3<u32>, hi: vec3<u32>, own_lo: vec3<u32>, own_hi: vec3<u32>) {
    test_cells(lo, hi, own_lo, own_hi);
}
