//! `gridrt bench-trace SCENE`: Mrays/s of the CPU reference (all threads) and the GPU trace
//! pass on the same primary (camera) and random rays, in one run. Prints; asserts nothing.

use std::time::Instant;

use gridrt_gpu::GpuSession;
use gridrt_grid::trace::TraceOptions;
use gridrt_scene::Camera;
use gridrt_scene::rays::{camera_rays, random_rays};
use serde_json::json;

use super::build_grid;
use crate::cli::BenchTraceArgs;

pub fn run(args: BenchTraceArgs) -> anyhow::Result<()> {
    let (mesh, report) = super::load_scene(&args.scene)?;
    let tris = mesh.triangles();
    let b = mesh.bounds();
    let (grid, build) = build_grid(&tris, &args.grid.config()?)?;
    let ctx = super::gpu_context()?;
    let gpu = GpuSession::new(&ctx, &tris, b)?;
    let gs = gpu.upload(&grid)?;
    let opts = TraceOptions { traversal: args.traversal, mailbox: true };
    let sets =
        [("primary", camera_rays(&Camera::fit(&b, 4.0 / 3.0), args.rays)), ("random", random_rays(&b, args.rays, 1))];
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
    gpu.trace(&gs, &sets[0].1, args.traversal, true)?;
    let mut rows = Vec::new();
    for (name, rays) in &sets {
        let cpu_s = best(&mut || {
            grid.trace_batch(&tris, rays, opts, true);
        });
        let mut err = None;
        let gpu_s = best(&mut || {
            if let Err(e) = gpu.trace(&gs, rays, args.traversal, true) {
                err = Some(e);
            }
        });
        if let Some(e) = err {
            return Err(e.into());
        }
        let n = rays.len() as f64;
        rows.push(json!({"rays": name, "count": rays.len(), "cpu_mrays_s": n / cpu_s / 1e6, "gpu_mrays_s": n / gpu_s / 1e6, "gpu_over_cpu": cpu_s / gpu_s}));
    }
    if args.json {
        let out = json!({
            "scene": report.source, "triangles": tris.len(), "grid": grid.kind().name(), "traversal": args.traversal.short_name(),
            "build_ms": build.times.total(), "cpu_threads": rayon::current_num_threads(), "adapter": ctx.adapter_name(), "results": rows,
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
    println!("{:<8} {:>10} {:>14} {:>14} {:>9}", "rays", "count", "CPU Mrays/s", "GPU Mrays/s", "GPU/CPU");
    for r in &rows {
        println!(
            "{:<8} {:>10} {:>14.2} {:>14.2} {:>9.2}",
            r["rays"].as_str().unwrap_or(""),
            r["count"],
            r["cpu_mrays_s"].as_f64().unwrap_or(0.0),
            r["gpu_mrays_s"].as_f64().unwrap_or(0.0),
            r["gpu_over_cpu"].as_f64().unwrap_or(0.0)
        );
    }
    if ctx.info.device_type == wgpu::DeviceType::Cpu {
        // The question users ask first when the "GPU" loses: say what it is.
        println!(
            "note: the GPU is a software adapter running on the same CPU cores (README, \"Structures and CPU vs GPU\")"
        );
    }
    Ok(())
}
