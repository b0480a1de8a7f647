//! `gridrt bench --dynamic`: the survey's case for grids, measured. On every animated scene
//! (`<scenes>/animated`, default ../shared/scenes/animated) and a generated crowd of ≥ 1M
//! triangles, each frame is posed once; then every grid kind is rebuilt from scratch (and traced
//! in single rays and in coherent packets) and every
//! BVH strategy is rebuilt (obvhs BVH2 `fastest_build`, obvhs CWBVH, `bvh`'s `build_par`) or
//! refit (obvhs BVH2, built once with `medium_build`), and all trace the same 512×512 primary
//! rays and the same shadow rays (from the flat grid's primary hits; occlusion queries, each
//! structure stopping at its first hit). A warm-up frame counted for no one comes first (the
//! refit trees' setup, every first build into fresh memory), then the steady state is timed.
//! Build and trace time per frame are reported apart;
//! primary hits are compared with the flat grid's as in `gridrt bench`, shadow rays on whether
//! they are occluded.

use std::path::{Path, PathBuf};
use std::time::Instant;

use gridrt_grid::cell_plane::CellPlanes;
use gridrt_grid::trace::TraceOptions;
use gridrt_grid::{CostModel, GridConfig, GridKind, PacketOptions, structure};
use gridrt_scene::{Hit, LoadLimits, Ray};
use serde::Serialize;

use super::agree;
use crate::cli::BenchArgs;
use crate::lab::animation::FixedView;
use crate::lab::report::{print_table, progress, write_rows};
use crate::lab::scenes::{default_scenes, gltf_files};
use gridrt_scene::Player;

/// Image size of the dynamic frames.
const SIZE: u32 = 512;

/// One structure's strategy on one animated scene, averaged over the frames.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicRow {
    pub scene: String,
    pub triangles: usize,
    pub structure: String,
    /// "grid" or "peer".
    pub family: &'static str,
    /// "rebuild" every frame, or "refit" a tree built once (its build is `setup_ms`).
    pub strategy: &'static str,
    pub frames: usize,
    pub pose_ms: f64,
    pub setup_ms: f64,
    pub build_ms: f64,
    /// Primary and shadow rays, all threads.
    pub trace_ms: f64,
    /// Of `trace_ms`, the primary rays' and the shadow rays' (occlusion queries).
    pub primary_ms: f64,
    pub shadow_ms: f64,
    /// build + trace (pose is the same for everyone and reported apart).
    pub total_ms: f64,
    /// Primary rays whose hit disagrees with the flat grid's (see `agree`) and shadow rays
    /// whose occlusion does.
    pub mismatches: u64,
    /// The rays compared with the flat grid's (every frame's primary and shadow rays).
    pub compared_rays: u64,
}

/// The best grid against the best BVH strategy on one scene.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicTarget {
    pub scene: String,
    pub triangles: usize,
    pub best_grid: String,
    pub best_bvh: String,
    /// best BVH total / best grid total: the goal is ≥ 1.5.
    pub speedup: f64,
    pub build_speedup: f64,
    pub trace_ratio: f64,
    pub met: bool,
}

/// Most triangles `bvh`'s `update_shapes` is run on (see `bench_scene`).
#[cfg(feature = "peers")]
const BVH_UPDATE_MAX_TRIANGLES: usize = 50_000;

/// A strategy under test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Strategy {
    Grid(GridKind),
    /// The grid traced in coherent packets (primary and shadow rays).
    GridPackets(GridKind),
    #[cfg(feature = "peers")]
    Rebuild(super::peers::PeerKind),
    /// A tree of this peer built once (its setup) and updated every frame.
    #[cfg(feature = "peers")]
    Refit(super::peers::PeerKind),
}

impl Strategy {
    fn all(with_peers: bool) -> Vec<Strategy> {
        let mut v: Vec<Strategy> = GridKind::ALL.iter().map(|&k| Strategy::Grid(k)).collect();
        v.extend(GridKind::ALL.iter().map(|&k| Strategy::GridPackets(k)));
        #[cfg(feature = "peers")]
        if with_peers {
            use super::peers::PeerKind;
            v.extend([PeerKind::ObvhsFastest, PeerKind::ObvhsCwbvh, PeerKind::Bvh].map(Strategy::Rebuild));
            v.extend([PeerKind::ObvhsMedium, PeerKind::Bvh].map(Strategy::Refit));
        }
        let _ = with_peers;
        v
    }

    /// A tree built once and refit every frame (its first build is its setup).
    fn refit(self) -> bool {
        #[cfg(feature = "peers")]
        return matches!(self, Strategy::Refit(_));
        #[cfg(not(feature = "peers"))]
        false
    }

    fn name(self) -> String {
        match self {
            Strategy::Grid(k) => k.name().into(),
            Strategy::GridPackets(k) => format!("{k}, packets"),
            #[cfg(feature = "peers")]
            Strategy::Rebuild(p) => p.name().into(),
            #[cfg(feature = "peers")]
            Strategy::Refit(super::peers::PeerKind::Bvh) => "bvh, update_shapes".into(),
            #[cfg(feature = "peers")]
            Strategy::Refit(p) => format!("{}, refit", p.name()),
        }
    }
}

/// A structure built for one frame.
enum Built {
    /// A grid, and its packets (`None`: single rays).
    Grid(gridrt_grid::AnyGrid, Option<PacketOptions>),
    #[cfg(feature = "peers")]
    Peer(super::peers::PeerBvh),
}

impl Built {
    fn trace(&self, tris: &[[glam::Vec3; 3]], rays: &[Ray], opts: TraceOptions) -> Vec<Hit> {
        match self {
            Built::Grid(g, packets) => crate::lab::frame::trace_frame(g, tris, rays, SIZE as usize, opts, *packets).0,
            #[cfg(feature = "peers")]
            Built::Peer(p) => p.trace_batch(tris, rays, opts.query),
        }
    }
}

/// The animated scenes: every .glb/.gltf of `<scenes>/animated` (none with --procedural); the
/// generated crowd is added by the caller.
fn scene_files(args: &BenchArgs) -> Vec<PathBuf> {
    let dir = if args.procedural { None } else { args.scenes.clone().or_else(default_scenes) };
    let mut files = dir.and_then(|d| gltf_files(&d.join("animated")).ok()).unwrap_or_default();
    if args.quick {
        files.retain(|p| p.file_name().is_some_and(|f| f == "LittlestTokyo.glb" || f == "Fox.glb"));
    }
    files
}

pub fn run(args: &BenchArgs, cost: &CostModel) -> anyhow::Result<()> {
    let mut files = scene_files(args);
    let crowd_tubes = if args.quick { 20 } else { gridrt_scene::crowd::tubes_for(1_000_000) };
    let crowd = args.out.join("crowd.glb");
    std::fs::write(&crowd, gridrt_scene::crowd::crowd_glb(crowd_tubes, 1))?;
    files.push(crowd);
    let strategies = Strategy::all(!args.no_peers);
    let frames = args.frames.max(1) as usize;
    let packets = PacketOptions { tile: args.tile, mailbox: true };
    let pb = progress((files.len() * (frames + 1)) as u64, "dynamic");
    let mut rows = Vec::new();
    for f in &files {
        rows.extend(bench_scene(f, &strategies, (frames, packets), cost, &pb)?);
    }
    pb.finish_and_clear();
    let targets = evaluate(&rows);
    write_rows(&args.out, "bench-dynamic", &rows)?;
    write_rows(&args.out, "bench-dynamic-targets", &targets)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&serde_json::json!({"rows": rows, "targets": targets}))?);
        return Ok(());
    }
    print_table(
        &[
            "scene",
            "triangles",
            "structure",
            "strategy",
            "pose ms",
            "build ms",
            "trace ms",
            "(primary",
            "shadow)",
            "total ms",
            "mismatches",
        ],
        &rows
            .iter()
            .map(|r| {
                vec![
                    r.scene.clone(),
                    r.triangles.to_string(),
                    r.structure.clone(),
                    r.strategy.into(),
                    format!("{:.2}", r.pose_ms),
                    format!("{:.2}", r.build_ms),
                    format!("{:.2}", r.trace_ms),
                    format!("{:.2}", r.primary_ms),
                    format!("{:.2}", r.shadow_ms),
                    format!("{:.2}", r.total_ms),
                    r.mismatches.to_string(),
                ]
            })
            .collect::<Vec<_>>(),
    );
    println!();
    print_table(
        &["scene", "best grid", "best BVH strategy", "speedup (goal ≥ 1.5)", "build", "trace", "met"],
        &targets
            .iter()
            .map(|t| {
                vec![
                    t.scene.clone(),
                    t.best_grid.clone(),
                    t.best_bvh.clone(),
                    format!("{:.2}", t.speedup),
                    format!("{:.2}", t.build_speedup),
                    format!("{:.2}", t.trace_ratio),
                    if t.met { "yes".into() } else { "no".into() },
                ]
            })
            .collect::<Vec<_>>(),
    );
    println!("\nrows and targets in {}", args.out.display());
    Ok(())
}

fn bench_scene(
    path: &Path,
    strategies: &[Strategy],
    (frames, packets): (usize, PacketOptions),
    cost: &CostModel,
    pb: &indicatif::ProgressBar,
) -> anyhow::Result<Vec<DynamicRow>> {
    let name = path.file_name().map_or_else(|| path.display().to_string(), |f| f.to_string_lossy().into_owned());
    let loaded = gridrt_scene::gltf_load::load_rigged_path_with(path, &LoadLimits::default())?;
    anyhow::ensure!(!loaded.rig.clips().is_empty(), "{name}: no animation");
    let mut player = Player::new(loaded, 0);
    let clip = player.rig.clips()[0].clone();
    // `bvh`'s update re-inserts each moved triangle one by one, single-threaded: 0.64 s a frame
    // at 42k triangles, and LittlestTokyo's 142k did not get through its frames in 15 minutes.
    // Beyond the limit the strategy is left out (and says so).
    #[cfg(feature = "peers")]
    let kept: Vec<Strategy> = strategies
        .iter()
        .copied()
        .filter(|s| *s != Strategy::Refit(super::peers::PeerKind::Bvh) || player.tris.len() <= BVH_UPDATE_MAX_TRIANGLES)
        .collect();
    #[cfg(feature = "peers")]
    if kept.len() < strategies.len() {
        // On stderr even when the progress bar is hidden (not a terminal).
        pb.suspend(|| {
            eprintln!(
                "{name}: bvh update_shapes left out ({} triangles > {BVH_UPDATE_MAX_TRIANGLES}: it re-inserts every moved triangle one by one)",
                player.tris.len()
            )
        });
    }
    #[cfg(feature = "peers")]
    let strategies = &kept[..];
    let view = FixedView::new(&player.clip_bounds(16)?, SIZE, SIZE);
    let (primary, trace_opts) = (&view.primary, view.trace_options());
    let mut shadow = Vec::new();
    // Per strategy, summed over the frames; and the refit tree between frames.
    #[derive(Clone, Copy, Default)]
    struct Totals {
        setup_ms: f64,
        build_ms: f64,
        trace_ms: f64,
        primary_ms: f64,
        mismatches: u64,
        compared_rays: u64,
    }
    let mut sums = vec![Totals::default(); strategies.len()];
    #[cfg(feature = "peers")]
    let mut refit_trees: Vec<Option<super::peers::PeerBvh>> = strategies.iter().map(|_| None).collect();
    // Each grid strategy rebuilds into its previous frame's arrays (as the refit tree keeps its
    // nodes): a rebuild every frame does not pay fresh memory's page faults again.
    let mut scratches: Vec<gridrt_grid::BuildScratch> = strategies.iter().map(|_| Default::default()).collect();
    let mut pose_ms = 0.0;
    // A warm-up frame first (the first frame's pose), counted for no strategy: the refit trees'
    // setup build, the grids' first build into fresh memory, every allocator's first frame.
    // The frames after it are the steady state of a scene played frame after frame.
    for (k, warm_up) in std::iter::once((0, true)).chain((0..frames).map(|k| (k, false))) {
        pb.set_message(format!("{name} · frame {k}{}", if warm_up { " (warm-up)" } else { "" }));
        let t = clip.start + clip.duration() * k as f64 / frames as f64;
        let start = Instant::now();
        player.pose(t)?;
        if !warm_up {
            pose_ms += start.elapsed().as_secs_f64() * 1e3;
        }
        let tris = &player.tris;
        let mut reference: Option<(Vec<Hit>, Vec<Hit>)> = None;
        for (s, &strategy) in strategies.iter().enumerate() {
            let start = Instant::now();
            let built = match strategy {
                Strategy::Grid(kind) | Strategy::GridPackets(kind) => Built::Grid(
                    structure::build_reusing(
                        tris,
                        &GridConfig {
                            kind,
                            cost: *cost,
                            cell_planes: CellPlanes::Auto.for_tracing(!matches!(strategy, Strategy::GridPackets(_))),
                            ..GridConfig::default()
                        },
                        &mut scratches[s],
                    )?
                    .0,
                    matches!(strategy, Strategy::GridPackets(_)).then_some(packets),
                ),
                #[cfg(feature = "peers")]
                Strategy::Rebuild(p) => Built::Peer(super::peers::build(p, tris)),
                #[cfg(feature = "peers")]
                Strategy::Refit(p) => Built::Peer(match refit_trees[s].take() {
                    Some(mut tree) => {
                        tree.refit(tris);
                        tree
                    }
                    None => super::peers::build(p, tris),
                }),
            };
            let built_at = Instant::now();
            let hits = built.trace(tris, primary, trace_opts);
            let primary_ms = built_at.elapsed().as_secs_f64() * 1e3;
            // The shadow rays come from the first strategy's hits, outside every timing.
            if reference.is_none() {
                crate::lab::frame::shadow_rays_from_hits(&view.shade, primary, &hits, &mut shadow);
            }
            // Shadow rays are occlusion queries (any hit) for every structure.
            let shadows_at = Instant::now();
            let shadow_hits = built.trace(tris, &shadow, trace_opts.occlusion());
            let trace_ms = primary_ms + shadows_at.elapsed().as_secs_f64() * 1e3;
            let sum = &mut sums[s];
            let build_ms = (built_at - start).as_secs_f64() * 1e3;
            if warm_up {
                if strategy.refit() {
                    sum.setup_ms += build_ms;
                }
            } else {
                sum.build_ms += build_ms;
                sum.trace_ms += trace_ms;
                sum.primary_ms += primary_ms;
            }
            // The first strategy (the flat grid) is the reference of the others.
            match &reference {
                Some((rp, rs)) => {
                    let differ = |a: &[Hit], b: &[Hit]| a.iter().zip(b).filter(|(x, y)| !agree(x, y)).count() as u64;
                    let occluded_differ =
                        shadow_hits.iter().zip(rs).filter(|(x, y)| x.is_hit() != y.is_hit()).count() as u64;
                    sum.mismatches += differ(&hits, rp) + occluded_differ;
                    sum.compared_rays += (hits.len() + shadow_hits.len()) as u64;
                }
                None => reference = Some((hits, shadow_hits)),
            }
            match (strategy, built) {
                (_, Built::Grid(grid, _)) => scratches[s].recycle(grid),
                #[cfg(feature = "peers")]
                (Strategy::Refit(_), Built::Peer(tree)) => refit_trees[s] = Some(tree),
                #[cfg(feature = "peers")]
                _ => {}
            }
        }
        pb.inc(1);
    }
    let n = frames as f64;
    Ok(strategies
        .iter()
        .zip(&sums)
        .map(|(&strategy, t)| {
            let grid = matches!(strategy, Strategy::Grid(_) | Strategy::GridPackets(_));
            let refit = strategy.refit();
            let Totals {
                setup_ms: setup,
                build_ms: build,
                trace_ms: trace,
                primary_ms: primary,
                mismatches: bad,
                compared_rays,
            } = *t;
            DynamicRow {
                scene: name.clone(),
                triangles: player.tris.len(),
                structure: strategy.name(),
                family: if grid { "grid" } else { "peer" },
                strategy: if refit { "refit" } else { "rebuild" },
                frames,
                pose_ms: pose_ms / n,
                setup_ms: setup,
                build_ms: build / n,
                trace_ms: trace / n,
                primary_ms: primary / n,
                shadow_ms: (trace - primary) / n,
                total_ms: (build + trace) / n,
                mismatches: bad,
                compared_rays,
            }
        })
        .collect())
}

/// Per scene: the best grid (least build + trace) against the best BVH strategy.
fn evaluate(rows: &[DynamicRow]) -> Vec<DynamicTarget> {
    let mut out = Vec::new();
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        // A peer strategy that answers many rays wrongly is no yardstick (as in `gridrt bench`).
        let best = |family: &str| {
            rows.iter()
                .filter(|r| r.scene == scene && r.family == family)
                .filter(|r| r.mismatches as f64 <= super::targets::MAX_WRONG_SHARE * r.compared_rays as f64)
                .min_by(|a, b| a.total_ms.total_cmp(&b.total_ms))
        };
        let (Some(g), Some(b)) = (best("grid"), best("peer")) else { continue };
        let speedup = b.total_ms / g.total_ms;
        out.push(DynamicTarget {
            scene: scene.into(),
            triangles: g.triangles,
            best_grid: g.structure.clone(),
            best_bvh: format!("{} ({})", b.structure, b.strategy),
            speedup,
            build_speedup: b.build_ms / g.build_ms,
            trace_ratio: b.trace_ms / g.trace_ms,
            met: speedup >= 1.5,
        });
    }
    out
}
