//! The render pass: deterministic across runs, and the same hit triangle per pixel as a CPU
//! rendering of the same camera (≥ 99.9% of pixels), for every grid kind; every view renders.

use gridrt_gpu::cpu::{camera_rays, gpu_camera, present_totals, shade_pixel, shadow_ray};
use gridrt_gpu::render::{MAX_TILE_PIXELS, shade_params, tile_limit};
use gridrt_gpu::trace::tile_quantum;
use gridrt_gpu::{FrameTarget, RenderOptions, View};
use gridrt_grid::trace::TraceOptions;
use gridrt_grid::{GridConfig, GridKind, structure};

use super::common::{default_scene, gpu, read_texture};

#[test]
fn default_scene_renders_deterministically_and_matches_the_cpu() {
    let Some(ctx) = gpu() else { return };
    let (tris, gpu) = default_scene(ctx);
    let (w, h) = (320, 240);
    let opts = RenderOptions::fit(&gpu.bounds, w, h);
    let cpu_rays = camera_rays(&gpu_camera(&opts.camera, w, h));
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    for kind in GridKind::ALL {
        let (grid, _) = structure::build(&tris, &GridConfig { kind, ..GridConfig::default() }).unwrap();
        let gs = gpu.upload(&grid).unwrap();
        let a = gpu.render(&gs, &opts).unwrap();
        let b = gpu.render(&gs, &opts).unwrap();
        assert_eq!(a.rgba, b.rgba, "{kind}: two renders differ");
        let (cpu_hits, _) = grid.trace_batch(&tris, &cpu_rays, TraceOptions::MAILBOX, true);
        let same = a.hits.iter().zip(&cpu_hits).filter(|(g, c)| g.triangle == c.triangle).count();
        let share = same as f64 / cpu_hits.len() as f64;
        let hit_pixels = cpu_hits.iter().filter(|h| h.is_hit()).count();
        println!(
            "{kind}: {:.4}% of pixels hit the same triangle on GPU and CPU ({hit_pixels} hit pixels)",
            100.0 * share
        );
        assert!(share >= 0.999, "{kind}: only {:.3}% of pixels agree", 100.0 * share);
        assert!(hit_pixels > (w * h / 10) as usize, "{kind}: the camera sees too little");
        // Not blank: several distinct colours.
        let mut colours: Vec<&[u8]> = a.rgba.chunks(4).collect();
        colours.sort();
        colours.dedup();
        assert!(colours.len() > 50, "{kind}: image looks blank ({} colours)", colours.len());
        if kind == GridKind::Flat {
            for view in View::ALL {
                let f = gpu.render(&gs, &RenderOptions { view, ..opts }).unwrap();
                assert_eq!(f.rgba.len(), (w * h * 4) as usize);
                write_ppm(&out.join(format!("default-{}.ppm", view.name())), w, h, &f.rgba);
            }
        }
    }
}

/// A frame larger than one tile (the device's binding limit or [`MAX_TILE_PIXELS`]) renders
/// in several tiles with the same hits as the CPU, no seam; a display target refuses a size
/// beyond the device's textures with an error instead of a device error.
#[test]
fn frames_larger_than_a_tile_render_exactly() {
    let Some(ctx) = gpu() else { return };
    let (tris, gpu) = default_scene(ctx);
    let (w, h) = (1200, 1000);
    assert!(u64::from(tile_limit(ctx)) < u64::from(w * h), "the frame must need several tiles");
    assert!(tile_limit(ctx) <= MAX_TILE_PIXELS);
    let (grid, _) = structure::build(&tris, &GridConfig::default()).unwrap();
    let gs = gpu.upload(&grid).unwrap();
    let opts = RenderOptions { view: View::Depth, ..RenderOptions::fit(&gpu.bounds, w, h) };
    let frame = gpu.render(&gs, &opts).unwrap();
    assert_eq!((frame.hits.len(), frame.rgba.len()), ((w * h) as usize, (w * h * 4) as usize));
    let rays = camera_rays(&gpu_camera(&opts.camera, w, h));
    let (cpu_hits, _) = grid.trace_batch(&tris, &rays, TraceOptions::MAILBOX, true);
    let same = frame.hits.iter().zip(&cpu_hits).filter(|(g, c)| g.triangle == c.triangle).count();
    println!("{w}x{h} in tiles of {}: {same} of {} pixels agree with the CPU", tile_limit(ctx), w * h);
    assert!(same as f64 >= 0.999 * cpu_hits.len() as f64, "{same} of {} pixels agree", cpu_hits.len());
    // Rows on both sides of every tile boundary agree too (no seam).
    let tile = tile_limit(ctx) as usize;
    for edge in (tile..(w * h) as usize).step_by(tile) {
        let (g, c) = (&frame.hits[edge - 64..edge + 64], &cpu_hits[edge - 64..edge + 64]);
        assert!(g.iter().zip(c).all(|(g, c)| g.triangle == c.triangle), "pixels around the tile edge {edge}");
    }
    ctx.check_device().unwrap();
    let max = ctx.device.limits().max_texture_dimension_2d;
    assert!(FrameTarget::new(ctx, max + 1, 16, true).is_err(), "a display texture over {max} pixels is refused");
    ctx.check_device().unwrap();
}

/// A tiny PPM writer so the test can leave images to look at without an image dependency.
fn write_ppm(path: &std::path::Path, w: u32, h: u32, rgba: &[u8]) {
    let mut data = format!("P6\n{w} {h}\n255\n").into_bytes();
    for p in rgba.chunks(4) {
        data.extend_from_slice(&p[..3]);
    }
    std::fs::write(path, data).unwrap();
}

/// The app's path: a display target gets the same pixels as the read-back render, its texture
/// holds them, and the GPU's frame totals equal the CPU sums (`present_totals`). The shading of
/// every view matches the CPU port (`shade_pixel`) within one step per channel.
#[test]
fn display_target_texture_totals_and_shading_match_the_cpu_ports() {
    let Some(ctx) = gpu() else { return };
    let (tris, gpu) = default_scene(ctx);
    // 128 × 4 bytes = 512: rows already meet the 256-byte copy alignment.
    let (w, h) = (128, 96);
    let fitted = RenderOptions { heat_max: 32.0, ..RenderOptions::fit(&gpu.bounds, w, h) };
    let camera = fitted.camera;
    let renderer = gpu.renderer().unwrap();
    let (grid, _) = structure::build(&tris, &GridConfig::default()).unwrap();
    let gs = gpu.upload(&grid).unwrap();
    let target = FrameTarget::new(ctx, w, h, true).unwrap();
    // The sampling view the app hands to egui is valid.
    let _view = target.display_view().unwrap();
    assert!(FrameTarget::new(ctx, w, h, false).unwrap().display_view().is_none());
    let cam = gpu_camera(&camera, w, h);
    let rays = camera_rays(&cam);
    let topts = TraceOptions::MAILBOX;
    let (cpu_hits, _) = grid.trace_batch(&tris, &rays, topts, true);
    for view in View::ALL {
        let opts = RenderOptions { view, ..fitted };
        let reference = gpu.render(&gs, &opts).unwrap();
        // Twice into the same target as one tile (buffers are reused, totals are cleared per
        // frame), then in tiles of an odd size (starts off any alignment), one submission each.
        let q = tile_quantum(ctx);
        for round in 0..3 {
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            if round < 2 {
                renderer.encode_tile(ctx, &mut enc, &gpu.source(&gs), &opts, &target, 0..w * h).unwrap();
            } else {
                let n = w * h;
                let mut first = 0;
                while first < n {
                    let count = (3 * q + 5).min(n - first);
                    renderer
                        .encode_tile(ctx, &mut enc, &gpu.source(&gs), &opts, &target, first..first + count)
                        .unwrap();
                    first += count;
                    if first < n {
                        ctx.queue.submit([enc.finish()]);
                        enc = ctx.device.create_command_encoder(&Default::default());
                    }
                }
                // A tile past the frame or over the target's capacity is refused, not mis-rendered.
                let mut e2 = ctx.device.create_command_encoder(&Default::default());
                assert!(renderer.encode_tile(ctx, &mut e2, &gpu.source(&gs), &opts, &target, 0..n + 1).is_err());
                assert!(renderer.encode_tile(ctx, &mut e2, &gpu.source(&gs), &opts, &target, n - 1..n + 1).is_err());
            }
            let texels = read_texture(ctx, &target, enc);
            assert_eq!(texels, reference.rgba, "{}: texture differs from the pixels (round {round})", view.name());
            let (tx, rx) = std::sync::mpsc::channel();
            target.totals_read.slice(..).map_async(wgpu::MapMode::Read, move |r| tx.send(r).unwrap());
            ctx.device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
            rx.recv().unwrap().unwrap();
            let totals = target.take_totals().unwrap();
            assert_eq!(totals, present_totals(&reference.hits, &reference.stats), "{}: frame totals", view.name());
            assert_eq!(totals.rays, w * h);
        }
        // CPU shading of the GPU's own hits and stats; shadow rays traced on the CPU.
        let shade = shade_params(&gpu.bounds, &opts);
        let shadow_rays: Vec<_> = rays.iter().zip(&reference.hits).map(|(r, hit)| shadow_ray(&shade, r, hit)).collect();
        let (shadow_hits, _) = grid.trace_batch(&tris, &shadow_rays, topts, true);
        let mut worst = 0u8;
        let mut off = 0usize;
        for i in 0..(w * h) as usize {
            let hit = &reference.hits[i];
            let tri = if hit.is_hit() { tris[hit.triangle as usize] } else { [glam::Vec3::ZERO; 3] };
            let c = shade_pixel(&shade, &rays[i], hit, &reference.stats[i], &shadow_hits[i], tri).to_le_bytes();
            let g = &reference.rgba[4 * i..4 * i + 4];
            let d = (0..4).map(|k| c[k].abs_diff(g[k])).max().unwrap();
            worst = worst.max(d);
            off += (d > 1) as usize;
        }
        println!("{}: {off} pixels differ from the CPU port by more than 1 (largest {worst})", view.name());
        // Shadow rays that graze an edge may flip between the GPU's FMA and the CPU's rounding.
        assert!(off * 1000 <= (w * h) as usize, "{}: {off} pixels differ from the CPU port", view.name());
        assert_eq!(
            reference.hits.iter().filter(|h| h.is_hit()).count(),
            cpu_hits.iter().filter(|h| h.is_hit()).count()
        );
    }
}
