//! `gridrt bench-trace SCENE`: Mrays/s of the CPU reference (all threads) and the GPU trace
//! pass on the same camera (auto and framed views) and random rays, in one run, and of the CPU's
//! and the GPU's coherent packets on the camera rays. Prints; asserts nothing. A scene or grid
//! the device cannot hold gets the CPU's figures alone, with a warning.

use std::time::Instant;

use gridrt_gpu::GpuSession;
use gridrt_grid::PacketOptions;
use gridrt_grid::trace::TraceOptions;
use gridrt_scene::Camera;
use gridrt_scene::rays::{image_rays, image_size, random_rays};
use serde_json::json;

use super::build_grid;
use crate::cli::BenchTraceArgs;
use crate::lab::sweep::fits_on_gpu;

pub fn run(args: BenchTraceArgs) -> anyhow::Result<()> {
    let (mesh, report) = super::load_scene(&args.scene)?;
    let tris = mesh.triangles();
    let b = mesh.bounds();
    let (grid, build) = build_grid(&tris, &args.grid.config()?)?;
    let ctx = super::gpu_context(None)?;
    let session = fits_on_gpu(GpuSession::new(&ctx, &tris, b), &report.source)?;
    let on_gpu = match &session {
        Some(gpu) => fits_on_gpu(gpu.upload(&grid), &format!("the {} grid", grid.kind()))?.map(|gs| (gpu, gs)),
        None => None,
    };
    let opts = TraceOptions { traversal: args.traversal, mailbox: true, ..Default::default() };
    // Camera rays as whole 4:3 images of about `--rays` pixels, so packets tile them.
    let (width, height) = image_size(args.rays, 4.0 / 3.0);
    let framed = crate::lab::views::framed_camera(&tris, &b, &grid, width as f32 / height as f32);
    let image = |cam: &Camera| Some(image_rays(cam, width, height));
    let sets = [
        ("primary", image(&Camera::fit(&b, width as f32 / height as f32))),
        ("framed", image(&framed)),
        ("random", None),
    ];
    let sets: Vec<(&str, Vec<gridrt_scene::Ray>, bool)> = sets
        .into_iter()
        .map(|(name, rays)| match rays {
            Some(r) => (name, r, true),
            None => (name, random_rays(&b, args.rays, 1), false),
        })
        .collect();
    let packets = PacketOptions { tile: args.tile, mailbox: true };
    let best = |f: &mut dyn FnMut()| {
        (0..args.repeat.max(1))
            .map(|_| {
                let s = Instant::now();
                f();
                s.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    // Warm-up on a whole set: compiles the pipeline and sizes the tracer's buffers, which a
    // few rays do not (the first full-size call also paid ~0.2 s on lavapipe).
    if let Some((gpu, gs)) = &on_gpu {
        gpu.trace(gs, &sets[0].1, opts)?;
    }
    let mut rows = Vec::new();
    for (name, rays, is_image) in &sets {
        // The hit share comes from the timed runs (every run gives the same hits).
        let mut hits = 0;
        let cpu_s = best(&mut || {
            hits = grid.trace_batch(&tris, rays, opts, true).1.hits;
        });
        // Packets only where the rays are an image.
        let packet_s = is_image.then(|| {
            best(&mut || {
                grid.trace_packets(&tris, rays, width as usize, opts, packets, true);
            })
        });
        let mut err = None;
        let gpu_s = on_gpu.as_ref().map(|(gpu, gs)| {
            best(&mut || {
                if let Err(e) = gpu.trace(gs, rays, opts) {
                    err = Some(e);
                }
            })
        });
        // The GPU's 8×8 packet kernels, where the kind has one.
        let gpu_packets = *is_image && gridrt_gpu::Kernel::for_kind(grid.kind()).packet_file().is_some();
        let gpu_packet_s = on_gpu.as_ref().filter(|_| gpu_packets).map(|(gpu, gs)| {
            best(&mut || {
                if let Err(e) = gpu.trace_image(gs, rays, width, opts) {
                    err = Some(e);
                }
            })
        });
        if let Some(e) = err {
            return Err(e.into());
        }
        let n = rays.len() as f64;
        rows.push(
            json!({"rays": name, "count": rays.len(), "hit_share": hits as f64 / n, "cpu_mrays_s": n / cpu_s / 1e6,
            "cpu_packets_mrays_s": packet_s.map(|s| n / s / 1e6), "packets_over_single": packet_s.map(|s| cpu_s / s),
            "gpu_mrays_s": gpu_s.map(|s| n / s / 1e6), "gpu_over_cpu": gpu_s.map(|s| cpu_s / s),
            "gpu_packets_mrays_s": gpu_packet_s.map(|s| n / s / 1e6),
            "gpu_packets_over_single": gpu_packet_s.zip(gpu_s).map(|(p, s)| s / p)}),
        );
    }
    if args.json {
        let out = json!({
            "scene": report.source, "triangles": tris.len(), "grid": grid.kind().name(), "traversal": args.traversal.short_name(),
            "build_ms": build.times.total(), "packet_tile": args.tile, "cpu_threads": rayon::current_num_threads(), "adapter": ctx.adapter_name(), "results": rows,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "{} ({} triangles), {} grid, {}, CPU {} threads, GPU {}",
        report.source,
        tris.len(),
        grid.kind(),
        args.traversal,
        rayon::current_num_threads(),
        ctx.adapter_name()
    );
    let tile = args.tile;
    println!(
        "{:<8} {:>10} {:>6} {:>12} {:>16} {:>9} {:>12} {:>8} {:>12} {:>9}",
        "rays",
        "count",
        "hits",
        "CPU Mrays/s",
        format!("{tile}x{tile} packets"),
        "speed-up",
        "GPU Mrays/s",
        "GPU/CPU",
        "GPU packets",
        "speed-up"
    );
    let num = |v: &serde_json::Value, digits: usize| v.as_f64().map_or("-".to_string(), |x| format!("{x:.digits$}"));
    for r in &rows {
        println!(
            "{:<8} {:>10} {:>5.0}% {:>12} {:>16} {:>9} {:>12} {:>8} {:>12} {:>9}",
            r["rays"].as_str().unwrap_or(""),
            r["count"],
            r["hit_share"].as_f64().unwrap_or(0.0) * 100.0,
            num(&r["cpu_mrays_s"], 2),
            num(&r["cpu_packets_mrays_s"], 2),
            num(&r["packets_over_single"], 2),
            num(&r["gpu_mrays_s"], 2),
            num(&r["gpu_over_cpu"], 2),
            num(&r["gpu_packets_mrays_s"], 2),
            num(&r["gpu_packets_over_single"], 2)
        );
    }
    if ctx.is_software() {
        // The question users ask first when the "GPU" loses: say what it is.
        println!(
            "note: the GPU is a software adapter running on the same CPU cores (README, \"Structures and CPU vs GPU\")"
        );
    }
    Ok(())
}
