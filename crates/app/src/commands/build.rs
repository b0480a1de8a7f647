//! `gridrt build SCENE`: resolution, cells, references, empty cells, memory, build ms per phase.

use serde_json::json;

use super::{Built, build_grid, human_bytes};
use crate::cli::BuildArgs;

pub fn run(args: BuildArgs) -> anyhow::Result<()> {
    let (mesh, report) = super::load_scene(&args.scene)?;
    let tris = mesh.triangles();
    let Built { grid, choice, times, options } = build_grid(&tris, &args.grid)?;
    let stats = grid.stats(tris.len());
    if args.json {
        let phases: serde_json::Map<String, serde_json::Value> =
            times.0.iter().map(|(k, v)| (k.clone(), json!(v))).collect();
        let out = json!({
            "scene": report.source,
            "triangles": tris.len(),
            "grid": "flat",
            "insert": options.insert,
            "parallel": options.parallel,
            "threads": if options.parallel { rayon::current_num_threads() } else { 1 },
            "resolution_policy": choice.policy,
            "resolution": stats.resolution,
            "cells": stats.cells,
            "refs": stats.refs,
            "empty_cells": stats.empty_cells,
            "empty_percent": stats.empty_percent,
            "max_refs_per_cell": stats.max_refs_per_cell,
            "refs_per_triangle": stats.refs_per_triangle,
            "memory_bytes": stats.memory_bytes,
            "memory_bytes_per_triangle": stats.memory_bytes as f64 / tris.len() as f64,
            "build_ms": phases,
            "build_ms_total": times.total(),
            "cost_curve": choice.curve,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!("scene:        {} ({} triangles)", report.source, tris.len());
    println!(
        "grid:         flat, {:?} insertion, {}",
        options.insert,
        if options.parallel { "parallel" } else { "serial" }
    );
    println!(
        "resolution:   {} x {} x {} ({:?})",
        stats.resolution[0], stats.resolution[1], stats.resolution[2], choice.policy
    );
    println!("cells:        {}", stats.cells);
    println!(
        "refs:         {} ({:.2} per triangle, max {} in one cell)",
        stats.refs, stats.refs_per_triangle, stats.max_refs_per_cell
    );
    println!("empty cells:  {} ({:.1}%)", stats.empty_cells, stats.empty_percent);
    println!(
        "memory:       {} ({:.1} bytes per triangle)",
        human_bytes(stats.memory_bytes),
        stats.memory_bytes as f64 / tris.len() as f64
    );
    let phases: Vec<String> = times.0.iter().map(|(k, v)| format!("{k} {v:.2}")).collect();
    println!("build ms:     {:.2} total ({})", times.total(), phases.join(", "));
    if !choice.curve.is_empty() {
        println!("cost model T(m) = Tsetup + m*Tstep + (N_m/m^2)*Tinter, sampled:");
        println!("  {:>8} {:>16} {:>12} {:>10} {:>10}", "m", "resolution", "N_m", "mu", "T(m)");
        for s in &choice.curve {
            let mark = if s.resolution == choice.resolution { "  <- chosen" } else { "" };
            let r = format!("{}x{}x{}", s.resolution[0], s.resolution[1], s.resolution[2]);
            println!("  {:>8.1} {:>16} {:>12} {:>10.2} {:>10.3}{mark}", s.m, r, s.n_m, s.mu, s.cost);
        }
    }
    Ok(())
}
