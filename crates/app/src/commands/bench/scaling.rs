//! Build time against triangle count: procedural particle clouds (the point model) from 100k
//! to 2.4M triangles, built as a flat grid with the auto resolution and, with the `peers`
//! feature, as the `bvh` crate's and obvhs' fastest BVHs. The log–log slope of build time
//! against N says how close to linear each build is (1 = linear).

use gridrt_grid::{CostModel, GridConfig, structure};
use gridrt_scene::procedural;
use serde::Serialize;

use super::{Subject, best_of};
use crate::cli::BenchArgs;
use crate::commands::experiment::report::{Chart, Series, print_table, progress};

#[derive(Clone, Debug, Serialize)]
pub struct ScalePoint {
    pub structure: String,
    pub triangles: usize,
    pub build_ms: f64,
    /// Nanoseconds of build per triangle.
    pub ns_per_triangle: f64,
}

/// The triangle counts of the scaling run (`--quick`: small ones).
pub fn counts(args: &BenchArgs) -> Vec<usize> {
    if args.quick {
        vec![10_000, 20_000, 40_000]
    } else {
        let mut v = vec![100_000, 200_000, 400_000, 800_000, 1_600_000];
        v.push(args.scaling_max.max(1_600_000));
        v
    }
}

/// The subjects whose build is scaled: the flat grid and the peers' fastest builds.
fn subjects(args: &BenchArgs) -> Vec<Subject> {
    let mut v = vec![Subject::Grid(gridrt_grid::GridKind::Flat)];
    #[cfg(feature = "peers")]
    if !args.no_peers {
        v.push(Subject::Peer(super::peers::PeerKind::Bvh));
        v.push(Subject::Peer(super::peers::PeerKind::ObvhsFastest));
    }
    let _ = args;
    v
}

pub fn run(args: &BenchArgs, cost: &CostModel) -> anyhow::Result<Vec<ScalePoint>> {
    let counts = counts(args);
    let subjects = subjects(args);
    let pb = progress((counts.len() * subjects.len()) as u64, "scaling");
    let mut out = Vec::new();
    for &n in &counts {
        let tris = procedural::particles(n, 11).triangles();
        for &s in &subjects {
            pb.set_message(format!("{} · {n} triangles", s.name()));
            let (secs, r) = best_of(args.repeat, || -> anyhow::Result<()> {
                match s {
                    Subject::Grid(kind) => {
                        let cfg = GridConfig { kind, cost: *cost, ..GridConfig::default() };
                        structure::build(&tris, &cfg)?;
                    }
                    #[cfg(feature = "peers")]
                    Subject::Peer(p) => {
                        super::peers::build(p, &tris);
                    }
                }
                Ok(())
            });
            r?;
            out.push(ScalePoint {
                structure: s.name(),
                triangles: n,
                build_ms: secs * 1e3,
                ns_per_triangle: secs * 1e9 / n as f64,
            });
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    Ok(out)
}

/// Least-squares slope of log(build ms) against log(N) for one structure.
pub fn slope(points: &[ScalePoint], structure: &str) -> Option<f64> {
    let p: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.structure == structure && p.build_ms > 0.0)
        .map(|p| ((p.triangles as f64).ln(), p.build_ms.ln()))
        .collect();
    if p.len() < 2 {
        return None;
    }
    let n = p.len() as f64;
    let (mx, my) = (p.iter().map(|q| q.0).sum::<f64>() / n, p.iter().map(|q| q.1).sum::<f64>() / n);
    let sxx: f64 = p.iter().map(|q| (q.0 - mx).powi(2)).sum();
    let sxy: f64 = p.iter().map(|q| (q.0 - mx) * (q.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

fn structures(points: &[ScalePoint]) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for p in points {
        if !v.contains(&p.structure) {
            v.push(p.structure.clone());
        }
    }
    v
}

pub fn print(points: &[ScalePoint]) {
    println!("build time against N (procedural particles):");
    let rows: Vec<Vec<String>> = points
        .iter()
        .map(|p| {
            vec![
                p.structure.clone(),
                p.triangles.to_string(),
                format!("{:.1}", p.build_ms),
                format!("{:.0}", p.ns_per_triangle),
            ]
        })
        .collect();
    print_table(&["structure", "triangles", "build ms", "ns/tri"], &rows);
    for s in structures(points) {
        if let Some(k) = slope(points, &s) {
            println!("  {s}: log–log slope {k:.3} (1 = linear)");
        }
    }
}

pub fn chart(points: &[ScalePoint]) -> Chart {
    Chart {
        title: "build time against triangle count (particles)".into(),
        x_label: "triangles".into(),
        y_label: "build ms".into(),
        log_x: true,
        log_y: true,
        series: structures(points)
            .into_iter()
            .map(|s| Series {
                points: points.iter().filter(|p| p.structure == s).map(|p| (p.triangles as f64, p.build_ms)).collect(),
                predicted: !s.starts_with("flat"),
                label: match slope(points, &s) {
                    Some(k) => format!("{s} (slope {k:.2})"),
                    None => s,
                },
            })
            .collect(),
        markers: Vec::new(),
        x_names: None,
    }
}
