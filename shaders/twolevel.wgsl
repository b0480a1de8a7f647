// Closest hit through a two-level grid (Kalojanov, Billeter & Slusallek).
//!include shared/hierarchy.wgsl

@compute @workgroup_size(64)
fn trace_twolevel(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x < params.res.w {
        trace_hierarchy(gid.x);
    }
}
