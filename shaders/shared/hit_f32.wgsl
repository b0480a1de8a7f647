// The hit's t, u, v from the sheared corners, in f32 (adapters without f64: WebGPU). The edge
// functions' signs are exact (Kahan's difference of products, shared/triangle.wgsl); their
// values, det and t are rounded in f32, so t, u, v may differ from the CPU's in the last bits.
// The f64 twin: shared/hit_f64.wgsl.

// x = t, y = u, z = v; w = 1 for a hit with det != 0, else 0. (Edges that overflowed f32 are
// NaN here, and so is t: no hit.)
fn hit_values(e: vec3<f32>, ax: f32, ay: f32, bx: f32, by: f32, cx: f32, cy: f32, z: vec3<f32>) -> vec4<f32> {
    let det = e.x + e.y + e.z;
    if det == 0.0 {
        return vec4<f32>(0.0);
    }
    let t = (e.x * z.x + e.y * z.y + e.z * z.z) / det;
    return vec4<f32>(t, e.y / det, e.z / det, 1.0);
}
