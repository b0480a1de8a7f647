// What the exact-insertion passes of the GPU grid build share: a triangle in grid space in f64
// (gridrt_grid::insert::prepare: (p − min) · inv_cell per coordinate) and its overlap test
// against cubes of half size 0.5 + margin.
//!include shared/build_triangles.wgsl
//!include shared/overlap.wgsl

fn exact_overlap_test(v: Vertices, p: BuildParams) -> OverlapTest {
    let min = d3_from_f32(p.grid_min.xyz);
    let inv = d3_from_f32(p.inv_cell.xyz);
    var corners = array<vec3<f32>, 3>(v.a, v.b, v.c);
    var g: array<D3, 3>;
    for (var i = 0u; i < 3u; i++) {
        g[i] = d3_mul(d3_sub(d3_from_f32(corners[i]), min), inv);
    }
    // 0.5 + 1/256 is exact in f32.
    return overlap_test_new(g, f64_from_f32(0.5 + p.margin));
}
