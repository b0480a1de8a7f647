//! `gridrt experiment hierarchy`: flat vs macrocell vs multi-resolution vs two-level vs
//! proximity clouds on every scene kind: build ms, memory, cells visited, triangle tests and
//! Mrays/s on the CPU (all threads) and the GPU, on the same rays (half primary, half random).

use gridrt_grid::{GridConfig, GridKind};
use serde::Serialize;

use crate::cli::ExperimentArgs;
use crate::lab::report::{Chart, Series, print_table, progress, save_chart, write_rows};
use crate::lab::scenes::{mixed_rays, pick_scenes};
use crate::lab::sweep::{machine, measure_config, session};

#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub scene: String,
    pub kind: String,
    pub triangles: usize,
    pub grid: &'static str,
    pub build_ms: f64,
    pub memory_bytes: u64,
    pub bytes_per_triangle: f64,
    pub mean_cells_per_ray: f64,
    pub mean_tests_per_ray: f64,
    pub cpu_mrays_s: f64,
    pub gpu_mrays_s: Option<f64>,
}

/// A chart: file stem, axis label, log axis, the value of a row.
type Metric = (&'static str, &'static str, bool, fn(&Row) -> Option<f64>);

pub fn run(args: &ExperimentArgs) -> anyhow::Result<()> {
    let scenes = pick_scenes(args)?;
    let ctx = crate::commands::gpu_unless(args.no_gpu)?;
    let rays_n = if args.quick { args.rays.min(10_000) } else { args.rays };
    let pb = progress((scenes.len() * GridKind::ALL.len()) as u64, "hierarchy");
    let mut rows = Vec::new();
    for sc in &scenes {
        pb.set_message(sc.name.clone());
        let rays = mixed_rays(&sc.bounds, rays_n, 3);
        let gpu = session(ctx.as_ref(), sc)?;
        for kind in GridKind::ALL {
            let cfg = GridConfig { kind, ..GridConfig::default() };
            let p = measure_config(&sc.tris, &cfg, &rays, gpu.as_ref(), 2)?;
            rows.push(Row {
                scene: sc.name.clone(),
                kind: sc.kind.clone(),
                triangles: sc.tris.len(),
                grid: kind.name(),
                build_ms: p.build_ms,
                memory_bytes: p.memory_bytes,
                bytes_per_triangle: p.memory_bytes as f64 / sc.tris.len().max(1) as f64,
                mean_cells_per_ray: p.mean_cells_per_ray,
                mean_tests_per_ray: p.mean_tests_per_ray,
                cpu_mrays_s: 1e3 / p.cpu_ns_per_ray,
                gpu_mrays_s: p.gpu_ns_per_ray.map(|ns| 1e3 / ns),
            });
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    write_rows(&args.out, "hierarchy", &rows)?;
    let names: Vec<String> = scenes.iter().map(|s| s.name.trim_end_matches(".glb").to_string()).collect();
    let metrics: [Metric; 5] = [
        ("cpu-mrays", "CPU Mrays/s", false, |r| Some(r.cpu_mrays_s)),
        ("gpu-mrays", "GPU Mrays/s", false, |r| r.gpu_mrays_s),
        ("tests", "triangle tests per ray", true, |r| Some(r.mean_tests_per_ray)),
        ("memory", "bytes per triangle", true, |r| Some(r.bytes_per_triangle)),
        ("build", "build ms", true, |r| Some(r.build_ms)),
    ];
    for (stem, label, log_y, f) in metrics {
        if stem == "gpu-mrays" && ctx.is_none() {
            continue;
        }
        let series = GridKind::ALL
            .iter()
            .map(|k| Series {
                label: k.name().into(),
                points: rows
                    .iter()
                    .filter(|r| r.grid == k.name())
                    .filter_map(|r| Some((names.iter().position(|n| r.scene.starts_with(n.as_str()))? as f64, f(r)?)))
                    .collect(),
                predicted: false,
            })
            .collect();
        let chart = Chart {
            title: format!("{label} by structure and scene"),
            x_label: "scene".into(),
            y_label: label.into(),
            log_x: false,
            log_y,
            series,
            markers: vec![],
            x_names: Some(names.clone()),
        };
        save_chart(&args.out, &format!("hierarchy-{stem}"), &chart)?;
    }
    println!("Structures compared, {} rays per scene (half primary, half random), {}:", rays_n, machine(ctx.as_ref()));
    print_table(
        &["scene", "grid", "build ms", "B/tri", "cells/ray", "tests/ray", "CPU Mrays/s", "GPU Mrays/s"],
        &rows
            .iter()
            .map(|r| {
                vec![
                    r.scene.clone(),
                    r.grid.to_string(),
                    format!("{:.1}", r.build_ms),
                    format!("{:.0}", r.bytes_per_triangle),
                    format!("{:.1}", r.mean_cells_per_ray),
                    format!("{:.1}", r.mean_tests_per_ray),
                    format!("{:.2}", r.cpu_mrays_s),
                    r.gpu_mrays_s.map_or("-".into(), |v| format!("{v:.2}")),
                ]
            })
            .collect::<Vec<_>>(),
    );
    println!("wrote hierarchy.csv, .json and hierarchy-*.svg/.png to {}", args.out.display());
    Ok(())
}
