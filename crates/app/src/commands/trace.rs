//! `gridrt trace SCENE --rays R -o HITS`: closest hits (or any hits, `--query any`), rays/s and
//! mean per-ray stats.

use std::time::Instant;

use anyhow::Context;
use clap::ValueEnum;
use gridrt_grid::trace::{TraceOptions, trace_batch};
use gridrt_grid::{BatchStats, Traversal, brute};
use gridrt_scene::rays::{read_rays, write_hits};
use serde_json::json;

use super::build_grid;
use crate::cli::{Backend, QueryArg, TraceArgs};

pub fn run(args: TraceArgs) -> anyhow::Result<()> {
    let (mesh, report) = super::load_scene(&args.scene)?;
    let rays = read_rays(&args.rays)?;
    let tris = mesh.triangles();
    if args.traversal == Traversal::Bresenham {
        eprintln!("warning: naive Bresenham is incomplete by design and misses hits (survey Figure 1)");
    }
    let opts = TraceOptions {
        traversal: args.traversal,
        mailbox: args.mailbox,
        interleave: !args.no_interleave,
        query: args.query.into(),
    };
    let (label, build_ms, memory, hits, stats, secs) = match args.backend {
        Backend::Brute => {
            // The closest hit is also a valid answer to an occlusion query.
            let start = Instant::now();
            let brute = brute::BruteForce::new(&tris);
            let (hits, stats) = trace_batch(&rays, true, |r| brute.trace(r));
            ("brute force".to_string(), 0.0, 0, hits, stats, start.elapsed().as_secs_f64())
        }
        Backend::Gpu => {
            let (grid, b) = build_grid(&tris, &args.grid.config()?)?;
            let ctx = super::gpu_context(Some(super::CpuRoute::BackendCpu))?;
            let gpu = super::on_device(gridrt_gpu::GpuSession::new(&ctx, &tris, mesh.bounds()))?;
            let gs = super::on_device(gpu.upload(&grid))?;
            // Warm-up (pipeline creation) outside the timing.
            gpu.trace(&gs, &rays[..rays.len().min(64)], opts)?;
            let start = Instant::now();
            let (hits, st) = gpu.trace(&gs, &rays, opts)?;
            let secs = start.elapsed().as_secs_f64();
            let mut stats = BatchStats::default();
            for (h, s) in hits.iter().zip(&st) {
                stats.add(*s, h.is_hit());
            }
            let label = format!(
                "{} on the GPU ({}), {}{}",
                grid.kind(),
                ctx.adapter_name(),
                args.traversal,
                if args.mailbox { " + mailbox" } else { "" }
            );
            (label, b.times.total(), b.stats.memory_bytes, hits, stats, secs)
        }
        Backend::Cpu => {
            let (grid, b) = build_grid(&tris, &args.grid.config()?)?;
            let start = Instant::now();
            let (hits, stats) = grid.trace_batch(&tris, &rays, opts, true);
            let r = b.stats.resolution;
            let label = format!(
                "{} {}x{}x{} {:?}, {}{}",
                grid.kind(),
                r[0],
                r[1],
                r[2],
                args.grid.config()?.build.insert,
                args.traversal,
                if args.mailbox { " + mailbox" } else { "" }
            );
            (label, b.times.total(), b.stats.memory_bytes, hits, stats, start.elapsed().as_secs_f64())
        }
    };
    write_hits(&args.output, &hits).with_context(|| format!("writing {}", args.output.display()))?;
    let summary = Summary { scene: &report.source, label: &label, build_ms, memory, secs };
    print_summary(&args, &summary, &stats)
}

struct Summary<'a> {
    scene: &'a str,
    label: &'a str,
    build_ms: f64,
    memory: u64,
    secs: f64,
}

fn print_summary(args: &TraceArgs, m: &Summary, s: &BatchStats) -> anyhow::Result<()> {
    let Summary { scene, label, build_ms, memory, secs } = *m;
    let rays_per_s = s.rays as f64 / secs.max(1e-9);
    if args.json {
        let out = json!({
            "scene": scene, "structure": label, "rays": s.rays, "hits": s.hits,
            "build_ms": build_ms, "memory_bytes": memory, "trace_s": secs, "rays_per_s": rays_per_s,
            "threads": rayon::current_num_threads(), "query": args.query.to_possible_value().map(|v| v.get_name().to_owned()),
            "mean_cells_per_ray": s.mean_cells(), "mean_tests_per_ray": s.mean_tests(),
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!("scene:      {scene}");
    println!("structure:  {label} (build {build_ms:.1} ms, {})", super::human_bytes(memory));
    println!("rays:       {} ({} hits, {:.1}%)", s.rays, s.hits, 100.0 * s.hits as f64 / s.rays.max(1) as f64);
    if args.query == QueryArg::Any {
        println!("query:      any hit (occlusion: whether each ray hits, not which hit)");
    }
    println!("time:       {:.3} s, {:.3} Mrays/s on {} threads", secs, rays_per_s / 1e6, rayon::current_num_threads());
    println!("per ray:    {:.2} cells visited, {:.2} triangle tests", s.mean_cells(), s.mean_tests());
    println!("hits file:  {}", args.output.display());
    Ok(())
}
