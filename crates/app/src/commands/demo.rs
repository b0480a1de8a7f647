//! `gridrt demo`: builds a grid over the embedded default scene, traces primary
//! and random rays with every exact traversal, checks a sample against brute force, and prints
//! a summary, no window needed.

use std::time::Instant;

use gridrt_grid::trace::{TraceOptions, trace_batch, trace_flat};
use gridrt_grid::{BuildOptions, CostModel, InsertMode, Resolution, Traversal, brute, build_flat};
use gridrt_scene::Camera;
use gridrt_scene::rays::{camera_rays, random_rays};

use super::human_bytes;

pub fn run() -> anyhow::Result<()> {
    let (mesh, report) = gridrt_scene::load_default();
    println!("gridrt demo: the embedded default scene (see `gridrt --help` for the commands)\n");
    println!("{report}\n");
    let tris = mesh.triangles();
    let (grid, choice, times) = build_flat(
        &tris,
        Resolution::Auto,
        &CostModel::default(),
        BuildOptions { insert: InsertMode::BoundingBox, parallel: true },
    )?;
    let st = grid.stats(tris.len());
    println!(
        "flat grid {}x{}x{} chosen by the cost model over {} samples: {} refs, {:.1}% empty, {}, built in {:.1} ms",
        st.resolution[0],
        st.resolution[1],
        st.resolution[2],
        choice.curve.len(),
        st.refs,
        st.empty_percent(),
        human_bytes(st.memory_bytes),
        times.total()
    );
    let b = mesh.bounds();
    let sets =
        [("primary", camera_rays(&Camera::fit(&b, 4.0 / 3.0), 200_000)), ("random", random_rays(&b, 200_000, 1))];
    println!("\n{:<8} {:<10} {:>10} {:>12} {:>12}", "rays", "traversal", "Mrays/s", "cells/ray", "tests/ray");
    for (name, rays) in &sets {
        for traversal in Traversal::EXACT {
            let opts = TraceOptions { traversal, mailbox: true, ..Default::default() };
            let start = Instant::now();
            let (_, s) = trace_batch(rays, true, |r| trace_flat(&grid, &tris, r, opts));
            let mrays = s.rays as f64 / start.elapsed().as_secs_f64() / 1e6;
            println!(
                "{name:<8} {:<10} {mrays:>10.2} {:>12.2} {:>12.2}",
                traversal.short_name(),
                s.mean_cells(),
                s.mean_tests()
            );
        }
    }
    // Spot check against the reference.
    let sample = &sets[1].1[..2000];
    let (grid_hits, _) = trace_batch(sample, true, |r| trace_flat(&grid, &tris, r, TraceOptions::default()));
    let brute = brute::BruteForce::new(&tris);
    let (ref_hits, _) = trace_batch(sample, true, |r| brute.trace(r));
    let same = grid_hits.iter().zip(&ref_hits).filter(|(a, b)| a.same_bits(b)).count();
    println!("\nbrute-force check: {same} of {} sampled rays identical", sample.len());
    anyhow::ensure!(same == sample.len(), "grid and brute force disagree");
    Ok(())
}
