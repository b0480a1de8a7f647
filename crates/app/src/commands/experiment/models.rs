//! `gridrt experiment models`: the resolution that is fastest in practice against the
//! triangle count N, for point-like (particles) and line-like (slivers) scenes of growing N.
//!
//! The survey (§3.2, eqs. 1–2) derives the optimal number of cells M = O(N) for the point
//! model and a much faster growth for the line model (it writes O(N^1.5)). For every N we sweep
//! the resolution over a wide interval, trace random rays on the CPU and take the fastest m;
//! then fit the log–log slope of the best cell count against N and compare. The cost model's
//! own choice (guess-and-check) is reported next to the measured optimum.

use glam::Vec3;
use gridrt_grid::resolution::{choose, count_refs, cubic_cells};
use gridrt_grid::{CostModel, InsertMode, Resolution};
use gridrt_scene::procedural;
use gridrt_scene::rays::random_rays;
use serde::Serialize;

use crate::cli::ExperimentArgs;
use crate::lab::report::{Chart, Series, fit_line, print_table, progress, save_chart, write_rows};
use crate::lab::sweep::{Point, measure};

/// Largest reference count a sweep point may have (2²⁷: 512 MiB of references).
const REF_BUDGET: u64 = 1 << 27;

#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub model: &'static str,
    pub n: usize,
    #[serde(flatten)]
    pub point: Point,
    /// The fastest resolution of this N.
    pub best: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub model: &'static str,
    pub n: usize,
    pub best_cells: u64,
    pub best_ns_per_ray: f64,
    /// Guess-and-check's choice with the survey's constants.
    pub cost_model_cells: u64,
    /// Its measured time relative to the best (1.0 = optimal).
    /// `None` when the choice holds more than the sweep's reference budget (not measured).
    pub cost_model_time_ratio: Option<f64>,
}

fn scene(model: &str, n: usize) -> (Vec<[Vec3; 3]>, gridrt_scene::Aabb) {
    let mesh = match model {
        "point (particles)" => procedural::particles(n, 1),
        _ => procedural::slivers(n, 1),
    };
    (mesh.triangles(), mesh.bounds())
}

pub fn run(args: &ExperimentArgs) -> anyhow::Result<()> {
    let ns: Vec<usize> = if args.quick { vec![2_000, 8_000] } else { vec![4_000, 16_000, 64_000, 256_000] };
    let rays_n = if args.quick { args.rays.min(5_000) } else { args.rays };
    let samples = if args.quick { 6 } else { 12 };
    let models = ["point (particles)", "line (slivers)"];
    let cost = CostModel::default();
    let pb = progress((models.len() * ns.len() * (samples + 1)) as u64, "models");
    let (mut rows, mut summary) = (Vec::new(), Vec::new());
    for model in models {
        for &n in &ns {
            let (tris, bounds) = scene(model, n);
            let rays = random_rays(&bounds, rays_n, 7);
            // Cells from N/8 to min(8·N^1.5, the memory cap): wide enough for both models.
            let lo = n as f64 / 8.0;
            let hi = (8.0 * (n as f64).powf(1.5)).min(cost.cell_cap(n) as f64).max(lo * 2.0);
            let mut points: Vec<Point> = Vec::new();
            for i in 0..samples {
                let cells = lo * (hi / lo).powf(i as f64 / (samples - 1) as f64);
                let res = cubic_cells(&bounds, cells);
                // Fine grids over line-like scenes hold billions of references (each sliver's box
                // covers thousands of cells): counted first in linear time, such a resolution is
                // reported and left out of the sweep instead of taking minutes and gigabytes.
                let refs = count_refs(&tris, &bounds, res, InsertMode::BoundingBox, true);
                if refs > REF_BUDGET {
                    pb.println(format!(
                        "{model}, N = {n}: skipping {cells:.0} cells: {refs} references (budget {REF_BUDGET})"
                    ));
                } else if !points.iter().any(|p| p.resolution == res) {
                    match measure(&tris, res, &rays, None, 2) {
                        Ok(p) => points.push(p),
                        Err(e) => pb.println(format!("{model}, N = {n}: skipping {cells:.0} cells: {e}")),
                    }
                }
                pb.inc(1);
            }
            let chosen = choose(&tris, &bounds, Resolution::Auto, &cost, InsertMode::BoundingBox, true);
            let choice_refs = count_refs(&tris, &bounds, chosen.resolution, InsertMode::BoundingBox, true);
            let at_choice = if choice_refs <= REF_BUDGET {
                Some(measure(&tris, chosen.resolution, &rays, None, 2)?)
            } else {
                pb.println(format!(
                    "{model}, N = {n}: the cost model's choice holds {choice_refs} references: not timed"
                ));
                None
            };
            pb.inc(1);
            let best = points.iter().min_by(|a, b| a.cpu_ns_per_ray.total_cmp(&b.cpu_ns_per_ray)).expect("points");
            summary.push(Summary {
                model,
                n,
                best_cells: best.cells,
                best_ns_per_ray: best.cpu_ns_per_ray,
                cost_model_cells: chosen.resolution.iter().map(|&r| r as u64).product(),
                cost_model_time_ratio: at_choice.map(|c| c.cpu_ns_per_ray / best.cpu_ns_per_ray),
            });
            let best_res = best.resolution;
            rows.extend(points.into_iter().map(|p| Row { model, n, best: p.resolution == best_res, point: p }));
        }
    }
    pb.finish_and_clear();
    write_rows(&args.out, "models", &rows)?;
    write_rows(&args.out, "models-summary", &summary)?;

    let mut series = Vec::new();
    let mut slopes = Vec::new();
    for model in models {
        let pts: Vec<(f64, f64)> =
            summary.iter().filter(|s| s.model == model).map(|s| (s.n as f64, s.best_cells as f64)).collect();
        let logs: Vec<(f64, f64)> = pts.iter().map(|p| (p.0.ln(), p.1.ln())).collect();
        slopes.push((model, fit_line(&logs).map(|f| f.0)));
        series.push(Series { label: format!("{model}: fastest cells"), points: pts, predicted: false });
        series.push(Series {
            label: format!("{model}: cost model's cells"),
            points: summary
                .iter()
                .filter(|s| s.model == model)
                .map(|s| (s.n as f64, s.cost_model_cells as f64))
                .collect(),
            predicted: true,
        });
    }
    save_chart(
        &args.out,
        "models",
        &Chart::log_log("Fastest resolution against N (CPU, random rays)", "triangles N", "cells M", series),
    )?;
    println!("Fastest flat-grid resolution against N ({rays_n} random rays, CPU):");
    print_table(
        &["model", "N", "best cells", "cells/N", "ns/ray", "cost-model cells", "its time / best"],
        &summary
            .iter()
            .map(|s| {
                vec![
                    s.model.to_string(),
                    s.n.to_string(),
                    s.best_cells.to_string(),
                    format!("{:.2}", s.best_cells as f64 / s.n as f64),
                    format!("{:.0}", s.best_ns_per_ray),
                    s.cost_model_cells.to_string(),
                    s.cost_model_time_ratio.map_or("not timed".into(), |r| format!("{r:.2}")),
                ]
            })
            .collect::<Vec<_>>(),
    );
    for (model, slope) in slopes {
        let claim = if model.starts_with("point") { 1.0 } else { 1.5 };
        match slope {
            Some(k) => println!(
                "{model}: best cells ∝ N^{k:.2} (survey: N^{claim}){}",
                if (k - claim).abs() > 0.25 { " — our data disagrees" } else { "" }
            ),
            None => println!("{model}: too few sizes for a slope"),
        }
    }
    println!("wrote models.csv, models-summary.csv, .json, models.svg, .png to {}", args.out.display());
    Ok(())
}
