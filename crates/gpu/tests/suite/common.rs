//! The shared GPU context (GPU tests fail when no adapter is found, unless
//! GRIDRT_SKIP_GPU_TESTS=1 is set explicitly, never in CI), and hostile test scenes.

use std::sync::OnceLock;

use glam::Vec3;
use gridrt_gpu::{GpuContext, GpuSession};

/// The device, or `None` when GPU tests are explicitly skipped.
pub fn gpu() -> Option<&'static GpuContext> {
    if std::env::var("GRIDRT_SKIP_GPU_TESTS").is_ok_and(|v| v == "1") {
        eprintln!("GRIDRT_SKIP_GPU_TESTS=1: skipping a GPU test");
        return None;
    }
    static CTX: OnceLock<GpuContext> = OnceLock::new();
    Some(CTX.get_or_init(|| match GpuContext::new_headless_blocking() {
        Ok(c) => {
            println!("GPU adapter: {}", c.adapter_name());
            c
        }
        Err(e) => panic!("no usable GPU adapter: {e}\n(install mesa-vulkan-drivers for lavapipe, or set GRIDRT_SKIP_GPU_TESTS=1 to skip GPU tests explicitly)"),
    }))
}

/// The embedded default scene on the test device: its triangles and a session over them.
pub fn default_scene(ctx: &'static GpuContext) -> (Vec<[Vec3; 3]>, GpuSession<'static>) {
    let (mesh, _) = gridrt_scene::load_default();
    let tris = mesh.triangles();
    let session = GpuSession::new(ctx, &tris, mesh.bounds()).unwrap();
    (tris, session)
}

/// Copies a display target's texture into a buffer (after what `enc` holds) and reads its RGBA8
/// texels back; the width times 4 must meet the 256-byte row alignment.
pub fn read_texture(ctx: &GpuContext, target: &gridrt_gpu::FrameTarget, mut enc: wgpu::CommandEncoder) -> Vec<u8> {
    let (w, h) = (target.width, target.height);
    let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: (w * h * 4) as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    enc.copy_texture_to_buffer(
        target.texture.as_ref().expect("a display target").as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(w * 4), rows_per_image: None },
        },
        wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
    );
    ctx.queue.submit([enc.finish()]);
    gridrt_gpu::trace::read_back(ctx, &readback, (w * h * 4) as u64, "texture").unwrap()
}

/// Hostile scenes for the GPU suites (the CPU's: crates/grid/tests/suite/hostile.rs): particles
/// at 1e-18 and at 1e29, and axis-aligned triangles on the planes of a 1/64 lattice of the unit
/// cube (on cell walls at many resolutions).
pub fn hostile_scenes() -> Vec<(&'static str, Vec<[Vec3; 3]>)> {
    use gridrt_scene::procedural::{self, SceneKind};
    let scaled = |s: f32| -> Vec<[Vec3; 3]> {
        procedural::generate(SceneKind::Particles, 3000, 7).mesh.triangles().iter().map(|t| t.map(|p| p * s)).collect()
    };
    let on_walls: Vec<[Vec3; 3]> = (0..3000u32)
        .map(|k| {
            let q = |i: u32| (i % 65) as f32 / 64.0;
            let (a, u, v) = ((k % 3) as usize, ((k + 1) % 3) as usize, ((k + 2) % 3) as usize);
            let (w, u0, v0) = (q(k.wrapping_mul(7919)), q(k.wrapping_mul(104_729)), q(k.wrapping_mul(1_299_709)));
            [0, 1, 2].map(|j| {
                let mut c = Vec3::ZERO;
                c[a] = w;
                c[u] = u0 + if j == 1 { 0.125 } else { 0.0 };
                c[v] = v0 + if j == 2 { 0.125 } else { 0.0 };
                c
            })
        })
        .collect();
    vec![("tiny (1e-18)", scaled(1e-18)), ("huge (1e29)", scaled(1e29)), ("on cell walls", on_walls)]
}
