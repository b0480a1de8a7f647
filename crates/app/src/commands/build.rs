//! `gridrt build SCENE`: resolution, cells, references, empty cells, memory, nodes and levels,
//! build ms per phase, the sampled cost curve and the cells digest; on the CPU or the GPU.

use serde_json::json;

use gridrt_grid::BuildReport;

use super::{build_grid, human_bytes};
use crate::cli::{BuildArgs, Device};

pub fn run(args: BuildArgs) -> anyhow::Result<()> {
    let (mesh, report) = super::load_scene(&args.scene)?;
    let tris = mesh.triangles();
    let cfg = args.grid.config()?;
    let (grid, b, adapter) = match args.backend {
        Device::Cpu => {
            let (grid, b) = build_grid(&tris, &cfg)?;
            (grid, b, None)
        }
        Device::Gpu => {
            let ctx = super::gpu_context(Some(super::CpuRoute::BackendCpu))?;
            let builder = gridrt_gpu::build::GridBuilder::new(&ctx)?;
            let scene = super::on_device(gridrt_gpu::upload::GpuScene::new(&ctx, &tris))?;
            let g = super::on_device(builder.build(&ctx, &scene, &tris, &cfg))?;
            let grid = builder.read_back(&ctx, &g)?;
            let b = BuildReport {
                kind: cfg.kind,
                triangles: tris.len(),
                resolution_choice: g.choice,
                macro_samples: g.macro_samples,
                times: g.times,
                stats: grid.stats(tris.len()),
            };
            (grid, b, Some(ctx.adapter_name()))
        }
    };
    let digest = format!("{:016x}", grid.cells_digest());
    let s = &b.stats;
    if args.json {
        let phases: serde_json::Map<String, serde_json::Value> =
            b.times.0.iter().map(|(k, v)| (k.clone(), json!(v))).collect();
        let out = json!({
            "scene": report.source,
            "triangles": tris.len(),
            "grid": cfg.kind.name(),
            "backend": format!("{:?}", args.backend).to_lowercase(),
            "adapter": adapter,
            "config": cfg,
            "threads": if cfg.build.parallel { rayon::current_num_threads() } else { 1 },
            "resolution": s.resolution,
            "nodes": s.nodes,
            "levels": s.levels,
            "depth_histogram": s.depth_histogram,
            "cells": s.cells,
            "refs": s.refs,
            "cells_digest": digest,
            "empty_cells": s.empty_cells,
            "empty_percent": s.empty_percent(),
            "memory_bytes": s.memory_bytes,
            "memory_bytes_per_triangle": s.memory_bytes_per_triangle,
            "structure": s,
            "build_ms": phases,
            "build_ms_total": b.times.total(),
            "cost_curve": b.resolution_choice.as_ref().map(|c| &c.curve),
            "macro_samples": b.macro_samples,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!("scene:        {} ({} triangles)", report.source, tris.len());
    println!(
        "grid:         {}, {:?} insertion, {}",
        cfg.kind,
        cfg.build.insert,
        match (&adapter, cfg.build.parallel) {
            (Some(a), _) => format!("built on the GPU ({a})"),
            (None, true) => "parallel".to_string(),
            (None, false) => "serial".to_string(),
        }
    );
    let r = s.resolution;
    match &b.resolution_choice {
        Some(c) => println!("resolution:   {} x {} x {} ({:?})", r[0], r[1], r[2], c.policy),
        None => println!("resolution:   {} x {} x {} (two-level top density)", r[0], r[1], r[2]),
    }
    println!("structure:    {} grids on {} levels, per level {:?}", s.nodes, s.levels, s.depth_histogram);
    if let Some(a) = s.macro_size {
        println!("macrocells:   {a}^3 fine cells each, {} occupied", s.occupied_macrocells.unwrap_or(0));
    }
    if let Some(j) = s.jump_cells {
        println!(
            "proximity:    {j} empty cells allow a jump (distance >= {})",
            gridrt_grid::proximity::MIN_JUMP_DISTANCE
        );
    }
    println!("cells:        {}", s.cells);
    println!("refs:         {} ({:.2} per triangle)", s.refs, s.refs as f64 / tris.len() as f64);
    println!("cells digest: {digest}");
    println!("empty cells:  {} ({:.1}%)", s.empty_cells, 100.0 * s.empty_cells as f64 / s.cells.max(1) as f64);
    println!("memory:       {} ({:.1} bytes per triangle)", human_bytes(s.memory_bytes), s.memory_bytes_per_triangle);
    let phases: Vec<String> = b.times.0.iter().map(|(k, v)| format!("{k} {v:.2}")).collect();
    println!("build ms:     {:.2} total ({})", b.times.total(), phases.join(", "));
    if let Some(choice) = b.resolution_choice.as_ref().filter(|c| !c.curve.is_empty()) {
        // The auto policy samples bounding-box insertion's N_m for either insertion mode.
        println!(
            "cost model T(m) = Tsetup + m*Tstep + (N_m/m^2)*Tinter (+ the memory term and its DRAM tier when their weights are set), \
             N_m of bounding-box insertion, sampled:"
        );
        println!("  {:>8} {:>16} {:>12} {:>10} {:>10}", "m", "resolution", "N_m", "mu", "T(m)");
        for c in &choice.curve {
            let mark = if c.resolution == choice.resolution { "  <- chosen" } else { "" };
            let res = format!("{}x{}x{}", c.resolution[0], c.resolution[1], c.resolution[2]);
            println!("  {:>8.1} {:>16} {:>12} {:>10.2} {:>10.3}{mark}", c.m, res, c.n_m, c.mu, c.cost);
        }
    }
    Ok(())
}
