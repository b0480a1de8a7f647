// The last pass of a displayed frame: copies the shaded pixels into the app's RGBA8 texture and
// sums the primary rays' stats (cells visited, triangle tests, hits) for the stats panel, so the
// app never reads the per-pixel buffers back. Sums are 64-bit (lo, hi words with carry): a
// 4k heatmap can exceed 2^32 cells. CPU port: crates/gpu/src/cpu.rs (`present_totals`).
//!include shared/render_bindings.wgsl

@group(0) @binding(0) var<uniform> shade: ShadeParams;
@group(0) @binding(1) var<storage, read> pixels: array<u32>;
@group(0) @binding(2) var<storage, read> primary_hits: array<Hit>;
@group(0) @binding(3) var<storage, read> primary_stats: array<RayStats>;
// Mirrors `FrameTotals`: cells lo/hi, tests lo/hi, hits, rays, 0, 0.
@group(0) @binding(4) var<storage, read_write> totals: array<atomic<u32>, 8>;
@group(0) @binding(5) var image: texture_storage_2d<rgba8unorm, write>;

// Per-workgroup partial sums: 64 rays per group stay far below 2^32 per counter.
var<workgroup> partial: array<atomic<u32>, 3>;

fn add64(lo: u32, v: u32) {
    let old = atomicAdd(&totals[lo], v);
    if old > 0xffffffffu - v {
        atomicAdd(&totals[lo + 1u], 1u);
    }
}

@compute @workgroup_size(64)
fn present(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let i = gid.x;
    let w = shade.width;
    let n = shade.pixel_count;
    // No early return: every invocation must reach the barrier.
    if i < n {
        let px = pixels[i];
        let c = vec4<f32>(f32(px & 0xffu), f32((px >> 8u) & 0xffu), f32((px >> 16u) & 0xffu), f32(px >> 24u)) / 255.0;
        let p = shade.first_pixel + i;
        textureStore(image, vec2<u32>(p % w, p / w), c);
        let st = primary_stats[i];
        atomicAdd(&partial[0], st.cells);
        atomicAdd(&partial[1], st.tests);
        if primary_hits[i].triangle != NO_HIT {
            atomicAdd(&partial[2], 1u);
        }
    }
    workgroupBarrier();
    if li == 0u {
        add64(0u, atomicLoad(&partial[0]));
        add64(2u, atomicLoad(&partial[1]));
        atomicAdd(&totals[4], atomicLoad(&partial[2]));
        atomicAdd(&totals[5], min(64u, n - min(n, i)));
    }
}
