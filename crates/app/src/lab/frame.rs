//! CPU frames: the render kernels' CPU ports (`gridrt_gpu::cpu`, one pixel each) over a whole
//! frame, in parallel. `render --backend cpu`, `animate`, `bench --dynamic` and the app's CPU
//! trace trace their frames with them.

use std::time::Instant;

use glam::Vec3;
use gridrt_gpu::RenderOptions;
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

/// What one frame cost and gave.
pub struct Rendered {
    pub rgba: Vec<u8>,
    pub hits: Vec<Hit>,
    pub primary_ms: f64,
    /// The shadow pass (shaded view): shadow rays from the primary hits and their trace.
    pub shadow_ms: Option<f64>,
    pub cells_per_ray: f64,
    pub tests_per_ray: f64,
    pub packets: PacketStats,
}

/// The frame on the CPU: primary rays, shadow rays from their hits, shading (the CPU ports of
/// the render kernels). `packets`: trace both passes in coherent packets.
pub fn cpu_frame(
    grid: &AnyGrid,
    tris: &[[glam::Vec3; 3]],
    bounds: &gridrt_scene::Aabb,
    opts: &RenderOptions,
    primary: &[Ray],
    packets: Option<PacketOptions>,
) -> Rendered {
    let shade = gridrt_gpu::render::shade_params(bounds, opts);
    let topts = gridrt_grid::TraceOptions { traversal: opts.traversal, mailbox: opts.mailbox, ..Default::default() };
    let width = opts.width as usize;
    // Per-ray counts only for the heatmaps (single rays; packets keep none).
    let per_ray = opts.view.is_heatmap();
    let trace = |rays: &[Ray],
                 topts: gridrt_grid::TraceOptions|
     -> (Vec<Hit>, Vec<gridrt_grid::RayStats>, gridrt_grid::BatchStats, PacketStats) {
        if per_ray && packets.is_none() {
            let (h, s): (Vec<Hit>, Vec<_>) = rays.par_iter().map(|r| grid.trace(tris, r, topts)).unzip();
            let mut b = gridrt_grid::BatchStats::default();
            h.iter().zip(&s).for_each(|(h, s)| b.add(*s, h.is_hit()));
            return (h, s, b, PacketStats::default());
        }
        let (h, b, ps) = trace_frame(grid, tris, rays, width, topts, packets);
        (h, Vec::new(), b, ps)
    };
    let start = Instant::now();
    let (hits, stats, batch, ps) = trace(primary, topts);
    let primary_ms = start.elapsed().as_secs_f64() * 1e3;
    let start = Instant::now();
    let mut shadow = Vec::new();
    shadow_rays_from_hits(&shade, primary, &hits, &mut shadow);
    // Shadow rays only ask whether anything occludes the light (any hit).
    let (shadow_hits, _, _, sps) = trace(&shadow, topts.occlusion());
    let shadow_ms = start.elapsed().as_secs_f64() * 1e3;
    let stats = per_ray.then_some(&stats[..]);
    let rgba = shade_pixels(&shade, tris, primary, &hits, stats, &shadow_hits);
    Rendered {
        rgba,
        hits,
        primary_ms,
        shadow_ms: Some(shadow_ms),
        cells_per_ray: batch.mean_cells(),
        tests_per_ray: batch.mean_tests(),
        packets: ps.merge(sps),
    }
}
