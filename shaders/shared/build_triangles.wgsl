// What the per-triangle passes of the GPU grid build share: the parameters, the scene's packed
// triangles (crates/gpu/src/upload.rs `pack_triangle`), and triangle i's vertices and cells.
//!include shared/build.wgsl

@group(0) @binding(0) var<uniform> params: BuildParams;
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;

// The triangle a per-triangle pass's invocation handles (64 per workgroup).
fn triangle_index(lid: u32, wid: vec3<u32>) -> u32 {
    return group_index(wid, params.groups_x) * 64u + lid;
}

fn triangle_vertices(i: u32) -> Vertices {
    return unpack_triangle(triangles[3u * i], triangles[3u * i + 1u], triangles[3u * i + 2u].x);
}
