//!include shared/types.wgsl
// The trace kernels' bindings (group 0, bindings 0-5; 6-7 are the structure's own).

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> rays: array<Ray>;
@group(0) @binding(2) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(3) var<storage, read_write> ray_stats: array<RayStats>;
// Three vec4 per triangle (w unused).
@group(0) @binding(4) var<storage, read> triangles: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> refs: array<u32>;
