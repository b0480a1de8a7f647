//! `gridrt experiment bresenham`: the share of the cells a ray crosses that a naive 3-D
//! Bresenham line misses (survey Figure 1), over random rays and grid sizes.
//!
//! Rays start uniformly inside an m³ grid (in cell units) with directions uniform on the
//! sphere and run to the grid's boundary. Amanatides–Woo gives the exact cell set (checked
//! against Cleary–Wyvill and Liu on every ray); Bresenham's cells are compared with it.

use std::collections::HashSet;

use glam::{UVec3, Vec3};
use gridrt_grid::geometry::GridRay;
use gridrt_grid::traversal::{Traversal, Walker};
use gridrt_scene::rng::Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::cli::ExperimentArgs;
use crate::lab::report::{Chart, Series, print_table, progress, save_chart, write_rows};

#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub m: u32,
    pub rays: u64,
    pub exact_cells_per_ray: f64,
    pub bresenham_cells_per_ray: f64,
    /// Crossed cells Bresenham does not visit, over all crossed cells.
    pub missed_share: f64,
    /// Rays with at least one missed cell.
    pub rays_missing_cells: f64,
    /// Bresenham cells the ray does not cross, over Bresenham's cells.
    pub extra_share: f64,
    /// Rays on which CW or Liu visited a different cell set than AW: they may differ on cells
    /// touched at a corner or an edge (zero length inside), which none of them must visit.
    pub exact_walker_disagreements: u64,
}

#[derive(Clone, Copy, Debug, Default)]
struct Counts {
    rays: u64,
    exact: u64,
    bres: u64,
    missed: u64,
    rays_missing: u64,
    extra: u64,
    disagree: u64,
}

impl std::ops::Add for Counts {
    type Output = Counts;
    fn add(self, o: Counts) -> Counts {
        Counts {
            rays: self.rays + o.rays,
            exact: self.exact + o.exact,
            bres: self.bres + o.bres,
            missed: self.missed + o.missed,
            rays_missing: self.rays_missing + o.rays_missing,
            extra: self.extra + o.extra,
            disagree: self.disagree + o.disagree,
        }
    }
}

fn cells(kind: Traversal, ray: &GridRay, res: UVec3) -> Vec<UVec3> {
    Walker::new(kind, ray, res).map(|s| s.cell).collect()
}

/// Counts for one random ray in an m³ grid.
fn one_ray(m: u32, seed: u64) -> Counts {
    let mut rng = Rng::new(seed);
    let res = UVec3::splat(m);
    let o = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * m as f32;
    let d = rng.unit_vector();
    let Some(ray) = GridRay::clipped(o, d, res, 0.0, f32::INFINITY) else { return Counts::default() };
    let exact = cells(Traversal::AmanatidesWoo, &ray, res);
    let exact_set: HashSet<UVec3> = exact.iter().copied().collect();
    let disagree = [Traversal::ClearyWyvill, Traversal::Liu]
        .into_iter()
        .any(|t| cells(t, &ray, res).into_iter().collect::<HashSet<_>>() != exact_set);
    let bres: HashSet<UVec3> = cells(Traversal::Bresenham, &ray, res).into_iter().collect();
    let missed = exact_set.iter().filter(|c| !bres.contains(c)).count() as u64;
    let extra = bres.iter().filter(|c| !exact_set.contains(c)).count() as u64;
    Counts {
        rays: 1,
        exact: exact_set.len() as u64,
        bres: bres.len() as u64,
        missed,
        rays_missing: u64::from(missed > 0),
        extra,
        disagree: u64::from(disagree),
    }
}

/// The rows for grid sizes `ms` with `rays` rays each.
pub fn measure(ms: &[u32], rays: usize, on_step: impl Fn()) -> Vec<Row> {
    ms.iter()
        .map(|&m| {
            let c = (0..rays as u64)
                .into_par_iter()
                .map(|i| one_ray(m, 0x5eed_0000 ^ (m as u64) << 32 ^ i))
                .reduce(Counts::default, |a, b| a + b);
            on_step();
            let n = c.rays.max(1) as f64;
            Row {
                m,
                rays: c.rays,
                exact_cells_per_ray: c.exact as f64 / n,
                bresenham_cells_per_ray: c.bres as f64 / n,
                missed_share: c.missed as f64 / c.exact.max(1) as f64,
                rays_missing_cells: c.rays_missing as f64 / n,
                extra_share: c.extra as f64 / c.bres.max(1) as f64,
                exact_walker_disagreements: c.disagree,
            }
        })
        .collect()
}

pub fn run(args: &ExperimentArgs) -> anyhow::Result<()> {
    let ms: Vec<u32> = if args.quick { vec![4, 16, 64] } else { vec![2, 4, 8, 16, 32, 64, 128, 256, 512] };
    let rays = if args.quick { args.rays.min(10_000) } else { args.rays };
    let pb = progress(ms.len() as u64, "bresenham");
    let rows = measure(&ms, rays, || pb.inc(1));
    pb.finish_and_clear();
    write_rows(&args.out, "bresenham", &rows)?;
    let pct = |f: fn(&Row) -> f64| rows.iter().map(|r| (r.m as f64, 100.0 * f(r))).collect::<Vec<_>>();
    save_chart(
        &args.out,
        "bresenham",
        &Chart {
            title: format!("Cells a naive 3-D Bresenham misses ({rays} random rays per grid)"),
            x_label: "grid resolution m (m³ cells)".into(),
            y_label: "%".into(),
            log_x: true,
            log_y: false,
            series: vec![
                Series { label: "crossed cells missed".into(), points: pct(|r| r.missed_share), predicted: false },
                Series {
                    label: "rays missing ≥ 1 cell".into(),
                    points: pct(|r| r.rays_missing_cells),
                    predicted: false,
                },
                Series {
                    label: "Bresenham cells not crossed".into(),
                    points: pct(|r| r.extra_share),
                    predicted: false,
                },
            ],
            markers: vec![],
            x_names: None,
        },
    )?;
    println!(
        "Naive 3-D Bresenham against the exact cell set (Amanatides–Woo = Cleary–Wyvill = Liu), {rays} random rays per m:"
    );
    print_table(
        &[
            "m",
            "exact cells/ray",
            "Bresenham cells/ray",
            "missed %",
            "rays missing %",
            "extra %",
            "AW≠CW/Liu (corner ties)",
        ],
        &rows
            .iter()
            .map(|r| {
                vec![
                    r.m.to_string(),
                    format!("{:.2}", r.exact_cells_per_ray),
                    format!("{:.2}", r.bresenham_cells_per_ray),
                    format!("{:.1}", 100.0 * r.missed_share),
                    format!("{:.1}", 100.0 * r.rays_missing_cells),
                    format!("{:.1}", 100.0 * r.extra_share),
                    r.exact_walker_disagreements.to_string(),
                ]
            })
            .collect::<Vec<_>>(),
    );
    println!("wrote bresenham.csv, .json, .svg, .png to {}", args.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bresenham_misses_a_substantial_share_and_the_exact_walkers_agree() {
        let rows = measure(&[8, 32], 2000, || {});
        for r in &rows {
            assert_eq!(r.rays, 2000, "every ray starts inside the grid");
            // The exact walkers may differ on a cell touched at a corner or edge (zero length).
            assert!(r.exact_walker_disagreements * 200 <= r.rays, "m = {}: {}", r.m, r.exact_walker_disagreements);
            // A line visits one cell per slice of its driving axis; a 3-D ray crosses up to
            // three times as many: a large share is missed, but never all of them.
            assert!(r.missed_share > 0.2 && r.missed_share < 0.8, "m = {}: {}", r.m, r.missed_share);
            assert!(r.bresenham_cells_per_ray < r.exact_cells_per_ray);
        }
        assert!(rows[1].exact_cells_per_ray > 3.0 * rows[0].exact_cells_per_ray, "longer walks on finer grids");
    }
}
