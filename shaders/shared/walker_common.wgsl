//!include shared/ray.wgsl
// What the three cell walkers share. Each walker lives in its own file with the same interface
// (`Walker`, `walker_init`, `walker_next`) and only its own state, and a kernel is composed with
// the one its pipeline walks (crates/gpu/src/shaders.rs, `{TRAVERSAL}` in an include): a small
// walker stays in registers, which matters most on the hierarchy stack (one walker per level).
// Naive Bresenham is CPU-only (it is incomplete by design).

fn sign_step(x: f32) -> i32 {
    if x > 0.0 {
        return 1;
    }
    if x < 0.0 {
        return -1;
    }
    return 0;
}
