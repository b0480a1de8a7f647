//! CPU frames: the render kernels' CPU ports (`gridrt_gpu::cpu`, one pixel each) over a whole
//! frame, in parallel. `render --backend cpu`, `animate` and `bench --dynamic` trace their frames
//! with them.

use glam::Vec3;
use gridrt_gpu::layout::ShadeParams;
use gridrt_grid::{AnyGrid, BatchStats, PacketOptions, PacketStats, RayStats, TraceOptions};
use gridrt_scene::{Hit, Ray};
use rayon::prelude::*;

/// A frame's rays (row-major, `width` per row) traced on all threads: in coherent packets when
/// `packets` is given (single rays for the kinds without packets), else one by one.
pub fn trace_frame(
    grid: &AnyGrid,
    tris: &[[Vec3; 3]],
    rays: &[Ray],
    width: usize,
    opts: TraceOptions,
    packets: Option<PacketOptions>,
) -> (Vec<Hit>, BatchStats, PacketStats) {
    match packets {
        Some(p) => grid.trace_packets(tris, rays, width, opts, p, true),
        None => {
            let (hits, stats) = grid.trace_batch(tris, rays, opts, true);
            (hits, stats, PacketStats::default())
        }
    }
}

/// shaders/shadow.wgsl `shadow_rays_from_hits` over a frame, in parallel, into `out` (reused).
pub fn shadow_rays_from_hits(shade: &ShadeParams, primary: &[Ray], hits: &[Hit], out: &mut Vec<Ray>) {
    out.clear();
    primary.par_iter().zip(hits).map(|(r, h)| gridrt_gpu::cpu::shadow_ray(shade, r, h)).collect_into_vec(out);
}

/// shaders/shade.wgsl `shade_pixels` over a frame, in parallel: RGBA8 bytes, row-major.
/// `stats`: the primary rays' counts for the heatmap views (zeros when `None`).
pub fn shade_pixels(
    shade: &ShadeParams,
    tris: &[[Vec3; 3]],
    primary: &[Ray],
    hits: &[Hit],
    stats: Option<&[RayStats]>,
    shadow_hits: &[Hit],
) -> Vec<u8> {
    let none = RayStats::default();
    (0..primary.len())
        .into_par_iter()
        .map(|i| {
            let tri = if hits[i].is_hit() { tris[hits[i].triangle as usize] } else { [Vec3::ZERO; 3] };
            let s = stats.map_or(&none, |s| &s[i]);
            gridrt_gpu::cpu::shade_pixel(shade, &primary[i], &hits[i], s, &shadow_hits[i], tri).to_le_bytes()
        })
        .flatten_iter()
        .collect()
}
