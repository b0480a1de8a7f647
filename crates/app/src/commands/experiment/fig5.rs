//! `gridrt experiment fig5`: the survey's Figure 5, the impact of the resolution on scenes of
//! different kinds. For each scene the flat grid's resolution is swept over the cost model's
//! interval (guess-and-check's samples, m from the point model's to the line model's optimum);
//! at each m we build, count N_m and memory, and time the same rays on the CPU (all threads) and
//! the GPU. The cost model's T(m), scaled to the CPU times by least squares, is overlaid, with
//! the auto-chosen m marked; the summary says how far the auto choice is from the measured
//! optimum.
//!
//! Scenes: from `--scenes DIR` (its manifest.json kinds: the two largest scanned models, the
//! largest architectural one, the particles and the slivers), else procedural stand-ins.

use gridrt_grid::resolution::{cubic_cells, sample_curve, samples_at};
use gridrt_grid::{CostModel, InsertMode};
use serde::Serialize;

use crate::cli::ExperimentArgs;
use crate::lab::report::{Chart, Series, print_table, progress, save_chart, write_rows};
use crate::lab::scenes::{mixed_rays, pick_scenes};
use crate::lab::sweep::{Point, machine, measure, session};

/// Sweep points below the survey's interval (down to half its low end).
const BELOW: usize = 4;

#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub scene: String,
    pub kind: String,
    pub triangles: usize,
    #[serde(flatten)]
    pub point: Point,
    /// The cost model's T(m) (its own units) and scaled to CPU nanoseconds per ray.
    pub predicted_cost: f64,
    pub predicted_cpu_ns: f64,
    /// Guess-and-check picked this m.
    pub auto: bool,
    /// Inside the survey's interval (the cost model's samples) or below it.
    pub in_interval: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub scene: String,
    pub kind: String,
    pub triangles: usize,
    pub auto_m: f64,
    pub best_cpu_m: f64,
    /// Measured time at the auto m over the best measured time (1.0 = optimal).
    pub auto_over_best_cpu: f64,
    pub best_gpu_m: Option<f64>,
    pub auto_over_best_gpu: Option<f64>,
}

pub fn run(args: &ExperimentArgs) -> anyhow::Result<()> {
    let scenes = pick_scenes(args)?;
    let ctx = crate::commands::gpu_unless(args.no_gpu)?;
    // The constants the command line's auto resolution uses: the calibration when saved.
    let (model, note) = crate::config::calibration::active_cost_model();
    eprintln!("fig5: cost model with {note}");
    let model = CostModel { samples: if args.quick { 6 } else { 16 }, ..model };
    let rays_n = if args.quick { args.rays.min(10_000) } else { args.rays };
    let pb = progress((scenes.len() * (model.samples as usize + BELOW)) as u64, "fig5");
    let (mut rows, mut summary) = (Vec::new(), Vec::new());
    for sc in &scenes {
        pb.set_message(sc.name.clone());
        // Half primary rays (from the auto camera), half random rays, as one set.
        let rays = mixed_rays(&sc.bounds, rays_n, 3);
        let gpu = session(ctx.as_ref(), sc)?;
        let interval = sample_curve(&sc.tris, &sc.bounds, &model, InsertMode::BoundingBox, true);
        let auto = model.best_sample(&interval).expect("a sample").resolution;
        // The measured optimum often sits at or below the interval's low end, (2N·Tinter/Tstep)^⅓:
        // the sweep starts at half of it.
        let below: Vec<[u32; 3]> = (1..=BELOW)
            .rev()
            .map(|k| cubic_cells(&sc.bounds, (interval[0].m * 2f64.powf(-(k as f64) / 4.0)).powi(3)))
            .filter(|r| r.iter().map(|&x| x as u64).product::<u64>() < interval[0].cells)
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect();
        let mut curve = samples_at(&sc.tris, &sc.bounds, &model, &below, InsertMode::BoundingBox, true);
        curve.sort_by_key(|s| s.cells);
        curve.extend(interval.iter().cloned());
        let mut pts = Vec::new();
        for s in &curve {
            pts.push((measure(&sc.tris, s.resolution, &rays, gpu.as_ref(), 2)?, s.cost));
            pb.inc(1);
        }
        pb.inc((model.samples as usize + BELOW).saturating_sub(curve.len()) as u64);
        // T(m) in CPU nanoseconds: the least-squares scale through the origin.
        let scale =
            pts.iter().map(|(p, c)| p.cpu_ns_per_ray * c).sum::<f64>() / pts.iter().map(|(_, c)| c * c).sum::<f64>();
        let best_cpu = pts.iter().min_by(|a, b| a.0.cpu_ns_per_ray.total_cmp(&b.0.cpu_ns_per_ray)).expect("points");
        let at_auto = pts.iter().find(|(p, _)| p.resolution == auto).expect("the auto m was measured");
        let best_gpu = pts
            .iter()
            .filter(|(p, _)| p.gpu_ns_per_ray.is_some())
            .min_by(|a, b| a.0.gpu_ns_per_ray.unwrap_or(0.0).total_cmp(&b.0.gpu_ns_per_ray.unwrap_or(0.0)));
        summary.push(Summary {
            scene: sc.name.clone(),
            kind: sc.kind.clone(),
            triangles: sc.tris.len(),
            auto_m: at_auto.0.m,
            best_cpu_m: best_cpu.0.m,
            auto_over_best_cpu: at_auto.0.cpu_ns_per_ray / best_cpu.0.cpu_ns_per_ray,
            best_gpu_m: best_gpu.map(|b| b.0.m),
            auto_over_best_gpu: best_gpu.and_then(|b| Some(at_auto.0.gpu_ns_per_ray? / b.0.gpu_ns_per_ray?)),
        });
        let series_of = |label: &str, f: &dyn Fn(&Point, f64) -> Option<f64>, predicted: bool| Series {
            label: label.into(),
            points: pts.iter().filter_map(|(p, c)| f(p, *c).map(|y| (p.m, y))).collect(),
            predicted,
        };
        let stem = sc.name.trim_end_matches(".glb").replace([' ', '(', ')'], "");
        let mut time_series = vec![
            series_of("CPU ns/ray (measured)", &|p, _| Some(p.cpu_ns_per_ray), false),
            series_of("cost model T(m), scaled to CPU", &|_, c| Some(c * scale), true),
        ];
        if ctx.is_some() {
            time_series.push(series_of("GPU ns/ray (measured)", &|p, _| p.gpu_ns_per_ray, false));
        }
        save_chart(
            &args.out,
            &format!("fig5-{stem}-time"),
            &Chart {
                title: format!("{} ({} triangles, {}): time per ray against m", sc.name, sc.tris.len(), sc.kind),
                x_label: "m = cbrt(cells)".into(),
                y_label: "ns per ray".into(),
                log_x: true,
                log_y: true,
                series: time_series,
                markers: vec![(at_auto.0.m, format!("auto m = {:.0}", at_auto.0.m))],
                x_names: None,
            },
        )?;
        save_chart(
            &args.out,
            &format!("fig5-{stem}-size"),
            &Chart {
                title: format!("{}: references N_m and memory against m", sc.name),
                x_label: "m = cbrt(cells)".into(),
                y_label: "count / bytes".into(),
                log_x: true,
                log_y: true,
                series: vec![
                    series_of("N_m (references)", &|p, _| Some(p.n_m as f64), false),
                    series_of("memory (bytes)", &|p, _| Some(p.memory_bytes as f64), false),
                    series_of("cells", &|p, _| Some(p.cells as f64), true),
                ],
                markers: vec![(at_auto.0.m, format!("auto m = {:.0}", at_auto.0.m))],
                x_names: None,
            },
        )?;
        rows.extend(pts.into_iter().map(|(p, c)| Row {
            scene: sc.name.clone(),
            kind: sc.kind.clone(),
            triangles: sc.tris.len(),
            auto: p.resolution == auto,
            in_interval: p.cells >= interval[0].cells,
            predicted_cpu_ns: c * scale,
            predicted_cost: c,
            point: p,
        }));
    }
    pb.finish_and_clear();
    write_rows(&args.out, "fig5", &rows)?;
    write_rows(&args.out, "fig5-summary", &summary)?;
    println!("Figure 5: flat grid, {} rays per point (half primary, half random), {}:", rays_n, machine(ctx.as_ref()));
    print_table(
        &["scene", "kind", "N", "auto m", "best m (CPU)", "auto/best CPU", "best m (GPU)", "auto/best GPU"],
        &summary
            .iter()
            .map(|s| {
                vec![
                    s.scene.clone(),
                    s.kind.clone(),
                    s.triangles.to_string(),
                    format!("{:.0}", s.auto_m),
                    format!("{:.0}", s.best_cpu_m),
                    format!("{:.2}", s.auto_over_best_cpu),
                    s.best_gpu_m.map_or("-".into(), |m| format!("{m:.0}")),
                    s.auto_over_best_gpu.map_or("-".into(), |r| format!("{r:.2}")),
                ]
            })
            .collect::<Vec<_>>(),
    );
    println!(
        "wrote fig5.csv, fig5-summary.csv, .json and fig5-<scene>-{{time,size}}.svg/.png to {}",
        args.out.display()
    );
    Ok(())
}
