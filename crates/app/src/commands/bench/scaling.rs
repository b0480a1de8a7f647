//! Build time against triangle count, on three procedural families scaled up: particle clouds
//! (the point model, triangles in random order: the worst case for memory locality) from 100k
//! to 2.4M triangles, once with a fixed particle size (the cloud gets more crowded: a grid holds
//! more references per triangle as N grows) and once with the size shrinking as N^(-1/3) (the
//! same cloud, finer), and fractal mountains (a coherent surface) from 131k to 2.1M. Each is
//! built as a flat grid with the auto resolution and, with the `peers` feature, as the `bvh`
//! crate's and obvhs' fastest BVHs. The log–log slope of build time against N says how close
//! to linear each build is (1 = linear); for the grid also against its references (its output).
//! Each point is the best of at least `--repeat` builds and of as many more as fit in a quarter
//! of a second (at most 10), so the small, fast points are not one cold build. The grid is
//! rebuilt into the previous build's arrays (`build_reusing`, as a dynamic scene's grid is
//! every frame), so every point is a rebuild into memory the process already has: with fresh
//! arrays, glibc serves arrays under 32 MiB from memory freed by the previous build but maps
//! larger ones afresh, so the small points were warm and the large ones paid their page faults
//! (the 2.4M particles' build 235 against 95 ms). The first build of each point (into fresh
//! memory) is reported beside it. The peers build as their crates do (fresh arrays).

use std::time::Instant;

use glam::Vec3;
use gridrt_grid::build::BuildScratch;
use gridrt_grid::{CostModel, GridConfig, structure};
use gridrt_scene::procedural;
use serde::Serialize;

use super::Subject;
use crate::cli::BenchArgs;
use crate::lab::report::{Chart, Series, print_table, progress};
use crate::lab::sweep::best_of;

#[derive(Clone, Debug, Serialize)]
pub struct ScalePoint {
    /// "particles", "particles, size ∝ N^-1/3" or "mountain".
    pub scene: &'static str,
    pub structure: String,
    pub triangles: usize,
    /// Triangle–cell references of the grid (0 for the BVHs).
    pub refs: u64,
    pub build_ms: f64,
    /// The point's first build (the grid's into fresh arrays).
    pub first_build_ms: f64,
    /// Nanoseconds of build per triangle.
    pub ns_per_triangle: f64,
}

/// The scenes of the scaling run: family, generator size, triangles (`--quick`: small ones).
pub fn cases(args: &BenchArgs) -> Vec<(&'static str, Vec<[Vec3; 3]>)> {
    let particles: Vec<usize> = if args.quick {
        vec![10_000, 20_000, 40_000]
    } else {
        vec![100_000, 200_000, 400_000, 800_000, 1_600_000, args.scaling_max.max(1_600_000)]
    };
    // A fractal mountain of level L has 2·4^L triangles.
    let levels: &[u32] = if args.quick { &[5, 6, 7] } else { &[8, 9, 10] };
    let first = particles[0] as f32;
    let mut out: Vec<(&'static str, Vec<[Vec3; 3]>)> =
        particles.iter().map(|&n| ("particles", procedural::particles(n, 11).triangles())).collect();
    // The same cloud at every N: the particles shrink as their spacing does (equal to the fixed
    // family's at the first size).
    out.extend(particles.iter().map(|&n| {
        let radius = procedural::PARTICLE_RADIUS * (first / n as f32).cbrt();
        ("particles, size ∝ N^-1/3", procedural::particles_of_radius(n, radius, 11).triangles())
    }));
    out.extend(levels.iter().map(|&l| ("mountain", procedural::fractal_mountain(l, 3).triangles())));
    out
}

/// The subjects whose build is scaled: the flat grid and the peers' fastest builds.
fn subjects(args: &BenchArgs) -> Vec<Subject> {
    #[cfg_attr(not(feature = "peers"), allow(unused_mut))]
    let mut v = vec![Subject::Grid(gridrt_grid::GridKind::Flat, gridrt_grid::InsertMode::BoundingBox)];
    #[cfg(feature = "peers")]
    if !args.no_peers {
        v.push(Subject::Peer(super::peers::PeerKind::Bvh));
        v.push(Subject::Peer(super::peers::PeerKind::ObvhsFastest));
    }
    let _ = args;
    v
}

pub fn run(args: &BenchArgs, cost: &CostModel) -> anyhow::Result<Vec<ScalePoint>> {
    let subjects = subjects(args);
    let cases = cases(args);
    let pb = progress((cases.len() * subjects.len()) as u64, "scaling");
    let mut out = Vec::new();
    for (scene, tris) in &cases {
        let (scene, tris, n) = (*scene, tris.as_slice(), tris.len());
        for &s in &subjects {
            pb.set_message(format!("{} · {n} triangles", s.name()));
            let ((secs, first), refs) = match s {
                super::Subject::Grid(kind, insert) => {
                    let mut cfg = GridConfig { kind, cost: *cost, ..GridConfig::default() };
                    cfg.build.insert = insert;
                    let mut scratch = BuildScratch::default();
                    let mut refs = 0;
                    let times = best_within(args.repeat as usize, || -> anyhow::Result<()> {
                        let (g, _) = structure::build_reusing(tris, &cfg, &mut scratch)?;
                        refs = g.stats(n).refs;
                        scratch.recycle(g);
                        Ok(())
                    });
                    times.1?;
                    (times.0, refs)
                }
                #[cfg(feature = "peers")]
                peer => {
                    let (times, built) = best_within(args.repeat as usize, || super::build(peer, tris, cost));
                    // A peer that failed on this size has no point.
                    if built?.is_none() {
                        pb.inc(1);
                        continue;
                    }
                    (times, 0)
                }
            };
            out.push(ScalePoint {
                scene,
                structure: s.name(),
                triangles: n,
                refs,
                build_ms: secs * 1e3,
                first_build_ms: first * 1e3,
                ns_per_triangle: secs * 1e9 / n as f64,
            });
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    Ok(out)
}

/// The best time of `f` over at least `repeat` runs and as many more as fit in
/// [`POINT_BUDGET_S`] (at most [`POINT_MAX_RUNS`]) with the first run's time, and the last
/// result.
fn best_within<T>(repeat: usize, mut f: impl FnMut() -> T) -> ((f64, f64), T) {
    let start = Instant::now();
    let (first, mut out) = best_of(1, &mut f);
    let (mut best, mut runs) = (first, 1);
    while runs < repeat || (runs < POINT_MAX_RUNS && start.elapsed().as_secs_f64() < POINT_BUDGET_S) {
        let (s, r) = best_of(1, &mut f);
        (best, out, runs) = (best.min(s), r, runs + 1);
    }
    ((best, first), out)
}

/// Seconds of builds a scaling point may take beyond `--repeat` ([`best_within`]).
const POINT_BUDGET_S: f64 = 0.25;
/// Most builds of one scaling point beyond `--repeat`.
const POINT_MAX_RUNS: usize = 10;

/// Least-squares slope of log(build ms) against log(N) for one structure on one family.
pub fn slope(points: &[ScalePoint], scene: &str, structure: &str) -> Option<f64> {
    slope_by(points, scene, structure, |p| p.triangles as f64, |p| p.build_ms)
}

/// [`slope`] of the points' first builds (into fresh memory).
pub fn slope_of_first(points: &[ScalePoint], scene: &str, structure: &str) -> Option<f64> {
    slope_by(points, scene, structure, |p| p.triangles as f64, |p| p.first_build_ms)
}

/// Least-squares slope of log(build ms) against log(references): how linear a grid build is in
/// its output.
pub fn slope_in_refs(points: &[ScalePoint], scene: &str, structure: &str) -> Option<f64> {
    slope_by(points, scene, structure, |p| p.refs as f64, |p| p.build_ms)
}

fn slope_by(
    points: &[ScalePoint],
    scene: &str,
    structure: &str,
    x: impl Fn(&ScalePoint) -> f64,
    y: impl Fn(&ScalePoint) -> f64,
) -> Option<f64> {
    let p: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.scene == scene && p.structure == structure && y(p) > 0.0 && x(p) > 0.0)
        .map(|p| (x(p).ln(), y(p).ln()))
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

/// The (family, structure) series in order of appearance.
fn series(points: &[ScalePoint]) -> Vec<(&'static str, String)> {
    let mut v: Vec<(&'static str, String)> = Vec::new();
    for p in points {
        if !v.iter().any(|(s, n)| *s == p.scene && *n == p.structure) {
            v.push((p.scene, p.structure.clone()));
        }
    }
    v
}

pub fn print(points: &[ScalePoint]) {
    println!("build time against N (procedural particles and mountains):");
    let rows: Vec<Vec<String>> = points
        .iter()
        .map(|p| {
            vec![
                p.scene.to_string(),
                p.structure.clone(),
                p.triangles.to_string(),
                if p.refs > 0 { p.refs.to_string() } else { "-".into() },
                format!("{:.1}", p.build_ms),
                format!("{:.1}", p.first_build_ms),
                format!("{:.0}", p.ns_per_triangle),
            ]
        })
        .collect();
    print_table(&["scene", "structure", "triangles", "refs", "build ms", "first build ms", "ns/tri"], &rows);
    for (scene, s) in series(points) {
        if let Some(k) = slope(points, scene, &s) {
            let first = slope_of_first(points, scene, &s).map_or(String::new(), |f| format!(", first builds {f:.3}"));
            match slope_in_refs(points, scene, &s) {
                Some(r) => {
                    println!("  {scene}, {s}: log–log slope {k:.3} in N{first}, {r:.3} in references (1 = linear)")
                }
                None => println!("  {scene}, {s}: log–log slope {k:.3}{first} (1 = linear)"),
            }
        }
    }
}

pub fn chart(points: &[ScalePoint]) -> Chart {
    Chart {
        title: "build time against triangle count (particles, mountains)".into(),
        x_label: "triangles".into(),
        y_label: "build ms".into(),
        log_x: true,
        log_y: true,
        series: series(points)
            .into_iter()
            .map(|(scene, s)| Series {
                points: points
                    .iter()
                    .filter(|p| p.scene == scene && p.structure == s)
                    .map(|p| (p.triangles as f64, p.build_ms))
                    .collect(),
                predicted: !s.starts_with("flat"),
                label: match slope(points, scene, &s) {
                    Some(k) => format!("{s}, {scene} (slope {k:.2})"),
                    None => format!("{s}, {scene}"),
                },
            })
            .collect(),
        markers: Vec::new(),
        x_names: None,
    }
}
