//! `gridrt experiment cost-constants`: Tsetup, Tstep and Tinter of T = Tsetup + m·Tstep +
//! μ·Tinter measured on this machine, for the CPU and the GPU backends.
//!
//! Each scene is traced with flat grids at several resolutions and with every other structure,
//! which spreads the per-ray cells visited (m) and triangle tests (μ) widely. A least-squares
//! fit of nanoseconds per ray against (1, cells/ray, tests/ray) gives the constants; the fit's
//! error (relative RMS residual and R²) says how well the survey's model explains the times.
//! The fit keeps every constant non-negative (a negative time has no meaning). A CPU
//! micro-benchmark (cells stepped through an empty grid, triangle tests against one
//! triangle) is reported beside the fit.
//!
//! `--save` stores the CPU constants in the calibration file ([`crate::config::calibration::path`]); the
//! command line's auto resolution then uses them instead of the survey's defaults.

use std::time::Instant;

use glam::{UVec3, Vec3};
use gridrt_grid::geometry::GridRay;
use gridrt_grid::ray::PreparedRay;
use gridrt_grid::resolution::sample_curve;
use gridrt_grid::traversal::{Traversal, Walker};
use gridrt_grid::triangle::intersect;
use gridrt_grid::{CostModel, GridConfig, GridKind, InsertMode, Resolution};
use gridrt_scene::rng::Rng;
use serde::Serialize;

use crate::cli::ExperimentArgs;
use crate::config::calibration::{Calibration, Fit};
use crate::lab::report::{Chart, Series, print_table, progress, save_chart, write_rows};
use crate::lab::scenes::{mixed_rays, pick_scenes};
use crate::lab::sweep::{machine, measure_config, session};

#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub scene: String,
    pub config: String,
    pub cells_per_ray: f64,
    pub tests_per_ray: f64,
    pub cpu_ns_per_ray: f64,
    pub gpu_ns_per_ray: Option<f64>,
}

/// Solves the least-squares problem restricted to the coefficients in `active` (the others are
/// 0): returns the full coefficient vector, or `None` if singular.
fn lsq_subset(points: &[(f64, f64, f64)], active: &[usize]) -> Option<[f64; 3]> {
    let k = active.len();
    let mut m = vec![vec![0.0f64; k + 1]; k];
    for &(x1, x2, y) in points {
        let v = [1.0, x1, x2];
        for i in 0..k {
            for j in 0..k {
                m[i][j] += v[active[i]] * v[active[j]];
            }
            m[i][k] += v[active[i]] * y;
        }
    }
    for col in 0..k {
        let pivot = (col..k).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        if m[pivot][col].abs() < 1e-12 {
            return None;
        }
        m.swap(col, pivot);
        let pivot_row = m[col].clone();
        for (row, r) in m.iter_mut().enumerate() {
            if row != col {
                let f = r[col] / pivot_row[col];
                for (x, p) in r.iter_mut().zip(&pivot_row).skip(col) {
                    *x -= f * p;
                }
            }
        }
    }
    let mut out = [0.0; 3];
    for (i, &a) in active.iter().enumerate() {
        out[a] = m[i][k] / m[i][i];
    }
    Some(out)
}

/// Least squares of y = a + b·x1 + c·x2 with a ≥ 0 and b, c > 0: times cannot be negative, and
/// a cost model without a step or a test cost has no optimum (a calibration with Tstep = 0 is
/// refused when loaded). The better of the full fit and the fit with a = 0, among those whose
/// coefficients qualify; `None` when neither does (the data cannot separate the constants).
pub fn fit3(points: &[(f64, f64, f64)]) -> Option<Fit> {
    if points.len() < 3 {
        return None;
    }
    let sse = |c: &[f64; 3]| points.iter().map(|&(x1, x2, y)| (c[0] + c[1] * x1 + c[2] * x2 - y).powi(2)).sum::<f64>();
    let subsets: [&[usize]; 2] = [&[0, 1, 2], &[1, 2]];
    // The unconstrained fit must be determined, else the data cannot separate the constants.
    lsq_subset(points, &[0, 1, 2])?;
    let [a, b, c] = subsets
        .iter()
        .filter_map(|s| lsq_subset(points, s))
        .filter(|c| c[0] >= 0.0 && c[1] > 0.0 && c[2] > 0.0)
        .min_by(|x, y| sse(x).total_cmp(&sse(y)))?;
    let mean = points.iter().map(|p| p.2).sum::<f64>() / points.len() as f64;
    let (mut ss_res, mut ss_tot, mut rel) = (0.0, 0.0, 0.0);
    for &(x1, x2, y) in points {
        let e = a + b * x1 + c * x2 - y;
        ss_res += e * e;
        ss_tot += (y - mean) * (y - mean);
        rel += (e / y.max(1e-12)).powi(2);
    }
    Some(Fit {
        t_setup: a,
        t_step: b,
        t_inter: c,
        rel_rms_error: (rel / points.len() as f64).sqrt(),
        r_squared: if ss_tot > 0.0 { 1.0 - ss_res / ss_tot } else { 1.0 },
        points: points.len(),
    })
}

/// CPU micro-benchmark: ns per cell stepped (AW through an empty 256³ grid) and per triangle
/// test (the watertight test of the closest-hit loop against one triangle).
fn micro_cpu() -> (f64, f64) {
    let res = UVec3::splat(256);
    let mut rng = Rng::new(11);
    let rays: Vec<GridRay> = (0..20_000)
        .filter_map(|_| {
            let o = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 256.0;
            GridRay::clipped(o, rng.unit_vector(), res, 0.0, f32::INFINITY)
        })
        .collect();
    let s = Instant::now();
    let steps: usize = rays.iter().map(|r| Walker::new(Traversal::AmanatidesWoo, r, res).count()).sum();
    let step_ns = s.elapsed().as_secs_f64() * 1e9 / steps.max(1) as f64;
    let tri = [Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
    let prays: Vec<gridrt_scene::Ray> = (0..200_000)
        .map(|_| {
            let o = Vec3::new(rng.range(-1.5, 1.5), rng.range(-1.5, 1.5), -2.0);
            gridrt_scene::Ray::new(o, Vec3::Z, 0.0, f32::INFINITY)
        })
        .collect();
    let prepared: Vec<PreparedRay> = prays.iter().filter_map(PreparedRay::new).collect();
    let s = Instant::now();
    let mut hits = 0usize;
    for pr in &prepared {
        hits += usize::from(intersect(pr, &tri).is_some());
    }
    let test_ns = s.elapsed().as_secs_f64() * 1e9 / prepared.len().max(1) as f64;
    std::hint::black_box(hits);
    (step_ns, test_ns)
}

pub fn run(args: &ExperimentArgs) -> anyhow::Result<()> {
    let scenes = pick_scenes(args)?;
    let ctx = crate::commands::gpu_unless(args.no_gpu)?;
    let rays_n = if args.quick { args.rays.min(10_000) } else { args.rays };
    let flat_samples = if args.quick { 3 } else { 6 };
    let pb = progress((scenes.len() * (flat_samples + 4)) as u64, "constants");
    let mut rows = Vec::new();
    for sc in &scenes {
        pb.set_message(sc.name.clone());
        let rays = mixed_rays(&sc.bounds, rays_n, 5);
        let gpu = session(ctx.as_ref(), sc)?;
        let model = CostModel { samples: flat_samples as u32, ..CostModel::default() };
        let mut configs: Vec<(String, GridConfig)> =
            sample_curve(&sc.tris, &sc.bounds, &model, InsertMode::BoundingBox, true)
                .iter()
                .map(|s| {
                    let r = s.resolution;
                    (
                        format!("flat {}x{}x{}", r[0], r[1], r[2]),
                        GridConfig {
                            kind: GridKind::Flat,
                            resolution: Some(Resolution::Explicit(r)),
                            ..GridConfig::default()
                        },
                    )
                })
                .collect();
        configs.extend(
            GridKind::ALL
                .into_iter()
                .filter(|k| *k != GridKind::Flat)
                .map(|k| (k.name().to_string(), GridConfig { kind: k, ..GridConfig::default() })),
        );
        for (name, cfg) in configs {
            let p = measure_config(&sc.tris, &cfg, &rays, gpu.as_ref(), 2)?;
            rows.push(Row {
                scene: sc.name.clone(),
                config: name,
                cells_per_ray: p.mean_cells_per_ray,
                tests_per_ray: p.mean_tests_per_ray,
                cpu_ns_per_ray: p.cpu_ns_per_ray,
                gpu_ns_per_ray: p.gpu_ns_per_ray,
            });
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    let cpu_pts: Vec<(f64, f64, f64)> =
        rows.iter().map(|r| (r.cells_per_ray, r.tests_per_ray, r.cpu_ns_per_ray)).collect();
    let gpu_pts: Vec<(f64, f64, f64)> =
        rows.iter().filter_map(|r| Some((r.cells_per_ray, r.tests_per_ray, r.gpu_ns_per_ray?))).collect();
    let cpu = fit3(&cpu_pts).ok_or_else(|| anyhow::anyhow!("the CPU measurements do not determine three constants"))?;
    let gpu = fit3(&gpu_pts);
    let (step_ns, test_ns) = micro_cpu();
    write_rows(&args.out, "cost-constants", &rows)?;
    let calibration = Calibration { cpu, gpu, machine: machine(ctx.as_ref()), date: crate::format::today() };
    std::fs::write(args.out.join("cost-constants-fit.json"), serde_json::to_string_pretty(&calibration)?)?;
    let scatter = |label: &str, pts: &[(f64, f64, f64)], f: &Fit| Series {
        label: label.into(),
        points: pts.iter().map(|&(c, t, y)| (f.t_setup + f.t_step * c + f.t_inter * t, y)).collect(),
        predicted: false,
    };
    let mut series = vec![scatter("CPU", &cpu_pts, &cpu)];
    if let Some(g) = &gpu {
        series.push(scatter("GPU", &gpu_pts, g));
    }
    let all: Vec<f64> =
        series.iter().flat_map(|s| s.points.iter().flat_map(|p| [p.0, p.1])).filter(|v| *v > 0.0).collect();
    let (lo, hi) = all.iter().fold((f64::MAX, 0.0f64), |a, &v| (a.0.min(v), a.1.max(v)));
    series.push(Series { label: "measured = predicted".into(), points: vec![(lo, lo), (hi, hi)], predicted: true });
    save_chart(
        &args.out,
        "cost-constants",
        &Chart::log_log(
            "Measured against fitted time per ray",
            "fitted Tsetup + m·Tstep + μ·Tinter (ns)",
            "measured ns per ray",
            series,
        ),
    )?;
    println!(
        "Cost constants fitted to {} configurations ({} rays each, half primary, half random):",
        rows.len(),
        rays_n
    );
    let line = |name: &str, f: &Fit| {
        vec![
            name.to_string(),
            format!("{:.1}", f.t_setup),
            format!("{:.2}", f.t_step),
            format!("{:.2}", f.t_inter),
            format!("{:.2}", f.t_inter / f.t_step),
            format!("{:.1}%", 100.0 * f.rel_rms_error),
            format!("{:.3}", f.r_squared),
        ]
    };
    let mut table = vec![line("CPU (fit)", &cpu)];
    if let Some(g) = &gpu {
        table.push(line("GPU (fit)", g));
    }
    let d = CostModel::default();
    table.push(vec![
        "survey".into(),
        format!("{}", d.t_setup),
        format!("{}", d.t_step),
        format!("{}", d.t_inter),
        format!("{:.2}", d.t_inter / d.t_step),
        "-".into(),
        "-".into(),
    ]);
    print_table(&["backend", "Tsetup ns", "Tstep ns", "Tinter ns", "Tinter/Tstep", "rel. RMS error", "R²"], &table);
    println!(
        "CPU micro-benchmark, one thread: {step_ns:.2} ns per cell step (empty 256³ grid), {test_ns:.2} ns per triangle test \
         (ratio {:.2}). The fit's constants are wall time per ray with all threads and absorb what the model \
         leaves out (descending hierarchies, mailboxes, cache misses).",
        test_ns / step_ns
    );
    if args.save {
        let path = calibration.save()?;
        println!(
            "saved the calibration to {} (auto resolution on the command line now uses the CPU constants)",
            path.display()
        );
    }
    println!("wrote cost-constants.csv, .json, cost-constants-fit.json, .svg, .png to {}", args.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_recovers_known_constants() {
        let pts: Vec<(f64, f64, f64)> = (0..30)
            .map(|i| {
                let (c, t) = (1.0 + (i * 7 % 13) as f64, 0.5 + (i * 5 % 11) as f64);
                (c, t, 20.0 + 3.0 * c + 9.0 * t)
            })
            .collect();
        let f = fit3(&pts).unwrap();
        assert!(
            (f.t_setup - 20.0).abs() < 1e-6 && (f.t_step - 3.0).abs() < 1e-9 && (f.t_inter - 9.0).abs() < 1e-9,
            "{f:?}"
        );
        assert!(f.rel_rms_error < 1e-9 && (f.r_squared - 1.0).abs() < 1e-9);
        // A negative intercept is not a time: the fit keeps Tsetup at 0 and refits the rest.
        let neg: Vec<(f64, f64, f64)> = pts.iter().map(|&(c, t, y)| (c, t, y - 25.0)).collect();
        let g = fit3(&neg).unwrap();
        assert!(g.t_setup == 0.0 && g.t_step > 0.0 && g.t_inter > 0.0, "{g:?}");
        // Collinear inputs do not determine three constants.
        assert!(fit3(&[(1.0, 2.0, 3.0), (2.0, 4.0, 5.0), (3.0, 6.0, 7.0)]).is_none());
    }
}
