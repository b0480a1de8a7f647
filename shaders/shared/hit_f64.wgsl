// The hit's t, u, v from the sheared corners, in f64 where the device has it (SHADER_F64,
// native adapters): the same operations as the CPU's exact test (crates/grid/src/triangle.rs,
// `intersect_with`: the edge functions as f64 differences of exact products, det, t, u and v in
// f64, rounded once to f32), so the hits are bit-identical to the CPU's and brute force's.
// The f32 twin: shared/hit_f32.wgsl.

// x = t, y = u, z = v; w = 1 for a hit, else 0. `e` (the f32 edge functions) is not used here.
fn hit_values(e: vec3<f32>, ax: f32, ay: f32, bx: f32, by: f32, cx: f32, cy: f32, z: vec3<f32>) -> vec4<f32> {
    let u = f64(cx) * f64(by) - f64(cy) * f64(bx);
    let v = f64(ax) * f64(cy) - f64(ay) * f64(cx);
    let w = f64(bx) * f64(ay) - f64(by) * f64(ax);
    // The CPU's sign test again, exact in f64: the f32 one (shared/triangle.wgsl) is a pre-filter
    // that never rejects a hit, but lets through the triangles whose f32 products overflow (NaN
    // edges, coordinates near 1e19 and beyond), which only this test decides.
    if (u < 0.0lf || v < 0.0lf || w < 0.0lf) && (u > 0.0lf || v > 0.0lf || w > 0.0lf) {
        return vec4<f32>(0.0);
    }
    let det = u + v + w;
    if det == 0.0lf {
        return vec4<f32>(0.0);
    }
    let t = (u * f64(z.x) + v * f64(z.y) + w * f64(z.z)) / det;
    return vec4<f32>(f32(t), f32(v / det), f32(w / det), 1.0);
}
