//! `gridrt bench`: every grid kind against the BVHs users would pick instead, in one run, on
//! the same meshes and the same ray sets (a camera the model fills, a view from inside for
//! architectural scenes, random rays in the bounds; see [`crate::lab::views`]): build time,
//! memory per triangle, the hit share of each set and Mrays/s (CPU, all threads; the GPU too for
//! the grids). Then build time against triangle count (procedural particles, 100k to ≥ 2M), a
//! check of the auto resolution against a sweep around it, and the targets as ratios
//! from this one run. Benchmarks print numbers; nothing here asserts a speed.
//!
//! Every structure's hits are compared with the flat grid's on every ray: a benchmark of wrong
//! answers is worthless, so disagreements are counted and printed.

pub mod dynamic;
#[cfg(feature = "peers")]
pub mod peers;
pub mod scaling;
pub mod targets;

use glam::Vec3;
use gridrt_gpu::GpuContext;
use gridrt_grid::trace::TraceOptions;
use gridrt_grid::{AnyGrid, CostModel, GridConfig, GridKind, InsertMode, PacketOptions, Resolution, structure};
use gridrt_scene::{Hit, Ray};
use serde::Serialize;

use crate::cli::BenchArgs;
use crate::lab::report::{Chart, Series, print_table, progress, save_chart, write_rows};
use crate::lab::scenes::{LabScene, default_scenes, every_scene, procedural_scenes};
use crate::lab::sweep::{best_of, fits_on_gpu, machine, session};
use crate::lab::views::{RayBatch, RaySet, hit_share, probe_grid, ray_sets};

/// One structure on one scene and one ray set (its build and memory figures stand on each of its
/// sets' rows).
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub scene: String,
    pub kind: String,
    pub triangles: usize,
    /// A grid kind's name, or a peer configuration's.
    pub structure: String,
    /// "grid" (single rays), "grid packets" (coherent packets, camera sets only) or "peer".
    pub family: &'static str,
    /// Best wall-clock build over the repetitions (auto resolution included for grids).
    pub build_ms: f64,
    pub memory_bytes: u64,
    pub bytes_per_triangle: f64,
    pub rays: RaySet,
    /// How many rays the set has.
    pub ray_count: u64,
    /// Share of the set's rays that hit something.
    pub hit_share: f64,
    pub mrays_s: f64,
    pub gpu_mrays_s: Option<f64>,
    /// Whether the build ran on all threads.
    pub parallel_build: bool,
    /// Whether it intersects triangles with the grids' watertight test (else its own).
    pub shared_triangle_test: bool,
    /// Rays of the set whose hit differs from the flat grid's: another triangle not within 1e-5
    /// relative t, or hit vs miss.
    pub mismatches: u64,
    /// Of those, the rays where brute force disagrees with the flat grid (the grid is wrong).
    pub flat_wrong: u64,
    /// Of those, the rays whose true hit lies closer than the peer's documented blind distance
    /// (obvhs' CWBVH clamps every box entry to t ≥ 1e-4, so it cannot see such hits).
    pub blind_near: u64,
}

/// A structure under test: a grid kind with an insertion mode, or (with the `peers` feature) a
/// peer configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Subject {
    Grid(GridKind, InsertMode),
    #[cfg(feature = "peers")]
    Peer(peers::PeerKind),
}

impl Subject {
    /// Every grid kind with bounding-box insertion, then every kind with exact insertion (fewer
    /// references, so fewer tests per ray and fewer bytes, at a slower build), then the peers.
    pub fn all(with_peers: bool) -> Vec<Subject> {
        #[cfg_attr(not(feature = "peers"), allow(unused_mut))]
        let mut v: Vec<Subject> =
            InsertMode::ALL.iter().flat_map(|&m| GridKind::ALL.iter().map(move |&k| Subject::Grid(k, m))).collect();
        #[cfg(feature = "peers")]
        if with_peers {
            v.extend(peers::PeerKind::ALL.iter().map(|&p| Subject::Peer(p)));
        }
        let _ = with_peers;
        v
    }
    pub fn parallel_build(self) -> bool {
        match self {
            Subject::Grid(..) => true,
            #[cfg(feature = "peers")]
            Subject::Peer(p) => p.parallel_build(),
        }
    }
    pub fn shared_test(self) -> bool {
        match self {
            Subject::Grid(..) => true,
            #[cfg(feature = "peers")]
            Subject::Peer(p) => p.shared_test(),
        }
    }
    /// The distance before which the structure cannot see hits, when it has one.
    pub fn blind_distance(self) -> Option<f32> {
        match self {
            Subject::Grid(..) => None,
            #[cfg(feature = "peers")]
            Subject::Peer(p) => p.blind_distance(),
        }
    }
    pub fn name(self) -> String {
        match self {
            Subject::Grid(k, InsertMode::BoundingBox) => k.name().to_string(),
            Subject::Grid(k, InsertMode::Exact) => format!("{}, exact", k.name()),
            #[cfg(feature = "peers")]
            Subject::Peer(p) => p.name().to_string(),
        }
    }
}

/// Whether two closest hits agree: the same triangle, or both hits within 1e-5 relative t
/// (a near-tie between triangles), or both misses.
pub fn agree(a: &Hit, b: &Hit) -> bool {
    match (a.is_hit(), b.is_hit()) {
        (false, false) => true,
        (true, true) => a.triangle == b.triangle || (a.t - b.t).abs() <= 1e-5 * a.t.abs().max(b.t.abs()),
        _ => false,
    }
}

/// The scenes: every scene of `--scenes`' manifest (default ../shared/scenes), or every
/// .glb/.gltf in the folder without a manifest, or the procedural stand-ins.
fn pick_scenes(args: &BenchArgs) -> anyhow::Result<Vec<LabScene>> {
    let dir = if args.procedural { None } else { args.scenes.clone().or_else(default_scenes) };
    match dir {
        Some(dir) => every_scene(&dir, args.quick),
        None => Ok(procedural_scenes(args.quick)),
    }
}

/// A built subject, ready to trace.
enum Built {
    Grid(AnyGrid, u64),
    #[cfg(feature = "peers")]
    Peer(peers::PeerBvh),
}

/// Builds `subject`; `None` for a peer library that failed on the scene (it panicked: obvhs'
/// CWBVH conversion indexes out of bounds on some scenes with coordinates near 1e29), which the
/// scene's other subjects go on without.
fn build(subject: Subject, tris: &[[Vec3; 3]], cost: &CostModel) -> anyhow::Result<Option<Built>> {
    Ok(match subject {
        Subject::Grid(kind, insert) => {
            let mut cfg = GridConfig { kind, cost: *cost, ..GridConfig::default() };
            cfg.build.insert = insert;
            let (g, report) = structure::build(tris, &cfg)?;
            Some(Built::Grid(g, report.stats.memory_bytes))
        }
        #[cfg(feature = "peers")]
        Subject::Peer(p) => peer_guard(p.name(), "build", || peers::build(p, tris)).map(Built::Peer),
    })
}

/// Runs a peer library's `step`, turning its panic into `None` with a warning: a bug in a peer
/// must not end the benchmark of the scene's grids.
#[cfg(feature = "peers")]
fn peer_guard<T>(name: &str, step: &str, f: impl FnOnce() -> T) -> Option<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f))
        .map_err(|_| log::warn!("{name} panicked in its {step}; left out of this scene"))
        .ok()
}

impl Built {
    fn memory_bytes(&self) -> u64 {
        match self {
            Built::Grid(_, m) => *m,
            #[cfg(feature = "peers")]
            Built::Peer(p) => p.memory_bytes(),
        }
    }
    /// `name`: the subject's, for the warning of a peer that panics.
    #[cfg_attr(not(feature = "peers"), allow(unused_variables))]
    fn trace(&self, name: &str, tris: &[[Vec3; 3]], rays: &[Ray]) -> Vec<Hit> {
        match self {
            Built::Grid(g, _) => {
                let opts = TraceOptions::MAILBOX;
                g.trace_batch(tris, rays, opts, true).0
            }
            // A peer that panics here misses every ray (its mismatch count shows it).
            #[cfg(feature = "peers")]
            Built::Peer(p) => peer_guard(name, "trace", || p.trace_batch(tris, rays, gridrt_grid::Query::Closest))
                .unwrap_or_else(|| vec![Hit::MISS; rays.len()]),
        }
    }
}

/// One subject's measurements on a scene: a speed per ray set (`None` where it was not traced:
/// packets on random rays) and the hits of the sets it traced.
struct Measured {
    structure: String,
    family: &'static str,
    subject: Subject,
    build_s: f64,
    memory: u64,
    speeds: Vec<Option<(f64, Option<f64>)>>,
    hits: Vec<Vec<Hit>>,
}

/// Build rounds per scene at least (`--repeat` when larger): builds are cheap next to the
/// traces, and their ratios need more rounds than the traces' to settle.
const BUILD_ROUNDS: usize = 9;

/// Seconds of trace rounds a scene may take beyond `--repeat`: small scenes get more rounds
/// (at most [`MAX_TRACE_ROUNDS`]), large ones `--repeat`.
const TRACE_ROUND_BUDGET_S: f64 = 2.0;
const MAX_TRACE_ROUNDS: usize = 8;

/// Whether timed trace rounds go on after `round` of them, begun at `start`: at least
/// `--repeat`, then more while they fit in [`TRACE_ROUND_BUDGET_S`] (at most
/// [`MAX_TRACE_ROUNDS`]).
fn another_round(round: usize, repeat: u32, start: std::time::Instant) -> bool {
    round < (repeat as usize).max(1)
        || (round < MAX_TRACE_ROUNDS && start.elapsed().as_secs_f64() < TRACE_ROUND_BUDGET_S)
}

/// Measures every subject on one scene, on every ray set; the grids that walk packets also in
/// `--tile` packets on the camera sets (a row of their own, family "grid packets").
fn bench_scene(
    sc: &LabScene,
    sets: &[RayBatch],
    args: &BenchArgs,
    cost: &CostModel,
    gpu: Option<&GpuContext>,
    pb: &indicatif::ProgressBar,
) -> anyhow::Result<Vec<Row>> {
    let gpu = session(gpu, sc)?;
    let mut reference: Option<Vec<Vec<Hit>>> = None;
    let mut rows = Vec::new();
    // Builds are timed interleaved, every subject once a round, and each keeps its best round:
    // the build targets are ratios between subjects, and this machine's speed drifts from one
    // second to the next (subject by subject, two builds each, the same scene's ratios moved 2×
    // between runs).
    let subjects = Subject::all(!args.no_peers);
    let mut builds: Vec<(f64, Option<anyhow::Result<Option<Built>>>)> =
        subjects.iter().map(|_| (f64::INFINITY, None)).collect();
    // Each round in another order (a fixed shuffle per round), so that no subject always
    // follows the same one: a build right after one that left rayon's threads awake, or
    // Embree's threads spinning, starts faster or slower than it would otherwise.
    let mut rng = gridrt_scene::rng::Rng::new(7);
    for _ in 0..(args.repeat as usize).max(BUILD_ROUNDS) {
        for k in shuffled(subjects.len(), &mut rng) {
            let (subject, (best, built)) = (subjects[k], &mut builds[k]);
            // A peer that failed once is not built again.
            if matches!(built, Some(Ok(None))) {
                continue;
            }
            pb.set_message(format!("{} · {} (build)", sc.name, subject.name()));
            // The previous round's structure is dropped first, outside the timing.
            *built = None;
            let (s, b) = best_of(1, || build(subject, &sc.tris, cost));
            *best = best.min(s);
            *built = Some(b);
        }
    }
    // A peer that failed is left out of the scene; a grid that failed is an error.
    let mut built: Vec<(Subject, f64, Built)> = Vec::new();
    for (subject, (build_s, b)) in subjects.into_iter().zip(builds) {
        if let Some(b) = b.expect("at least one build round")? {
            built.push((subject, build_s, b));
        }
    }
    // The traces are timed interleaved too, for the same reason as the builds: each round
    // traces every subject's sets once, in a shuffled order, and each keeps its best round (it
    // was each subject's rounds back to back: a burst of load on the machine then moved one
    // subject's speed and not the others', and the same ratio moved by up to 1.6× between runs).
    let packet_opts = PacketOptions { tile: args.tile, mailbox: true };
    let walks_packets: Vec<bool> = built.iter().map(|(_, _, b)| matches!(b, Built::Grid(..))).collect();
    let mut single_best = vec![vec![f64::INFINITY; sets.len()]; built.len()];
    let mut packet_best = vec![vec![f64::INFINITY; sets.len()]; built.len()];
    let mut single_hits: Vec<Vec<Vec<Hit>>> = vec![Vec::new(); built.len()];
    let mut packet_hits: Vec<Vec<Option<Vec<Hit>>>> = vec![vec![None; sets.len()]; built.len()];
    // Rounds beyond `--repeat` while they fit in TRACE_ROUND_BUDGET_S: a small scene's trace
    // takes a few milliseconds, which one pause of the machine moves by 10–20%.
    let traces_start = std::time::Instant::now();
    let mut round = 0;
    while another_round(round, args.repeat, traces_start) {
        for k in shuffled(built.len(), &mut rng) {
            let (subject, _, b) = &built[k];
            let name = subject.name();
            pb.set_message(format!("{} · {name} (trace, round {})", sc.name, round + 1));
            for (i, batch) in sets.iter().enumerate() {
                let (s, h) = best_of(1, || b.trace(&name, &sc.tris, &batch.rays));
                single_best[k][i] = single_best[k][i].min(s);
                if round == 0 {
                    single_hits[k].push(h);
                }
                if let (Built::Grid(g, _), true, Some(width)) = (b, walks_packets[k], batch.width) {
                    let opts = TraceOptions::MAILBOX;
                    let (s, (h, _, _)) =
                        best_of(1, || g.trace_packets(&sc.tris, &batch.rays, width, opts, packet_opts, true));
                    packet_best[k][i] = packet_best[k][i].min(s);
                    packet_hits[k][i].get_or_insert(h);
                }
            }
        }
        round += 1;
    }
    for (k, (subject, build_s, built)) in built.into_iter().enumerate() {
        pb.set_message(format!("{} · {}", sc.name, subject.name()));
        let memory = built.memory_bytes();
        let mut single = Measured {
            structure: subject.name(),
            family: if matches!(subject, Subject::Grid(..)) { "grid" } else { "peer" },
            subject,
            build_s,
            memory,
            speeds: Vec::new(),
            hits: std::mem::take(&mut single_hits[k]),
        };
        // A grid the device cannot hold has no GPU figures (a warning says why).
        let uploaded = match (&built, gpu.as_ref()) {
            (Built::Grid(g, _), Some(gpu)) => {
                fits_on_gpu(gpu.upload(g), &format!("{}, {}", sc.name, subject.name()))?.map(|gs| (gpu, gs))
            }
            _ => None,
        };
        for (i, batch) in sets.iter().enumerate() {
            let mut gpu_mrays = None;
            if let Some((gpu, gs)) = &uploaded {
                let rays = &batch.rays;
                // Untimed warm-up: pipeline creation and first upload.
                gpu.trace(gs, &rays[..rays.len().min(64)], TraceOptions::MAILBOX)?;
                let (s, r) = best_of(args.repeat as usize, || gpu.trace(gs, rays, TraceOptions::MAILBOX));
                r?;
                gpu_mrays = Some(rays.len() as f64 / s / 1e6);
            }
            single.speeds.push(Some((batch.rays.len() as f64 / single_best[k][i] / 1e6, gpu_mrays)));
        }
        let reference = reference.get_or_insert_with(|| single.hits.clone());
        let mut measured = vec![single];
        if walks_packets[k] {
            let mut packets = Measured {
                structure: format!("{}, {t}×{t} packets", subject.name(), t = args.tile),
                family: "grid packets",
                subject,
                build_s,
                memory,
                speeds: Vec::new(),
                hits: Vec::new(),
            };
            for (i, batch) in sets.iter().enumerate() {
                match packet_hits[k][i].take() {
                    Some(h) => {
                        packets.speeds.push(Some((batch.rays.len() as f64 / packet_best[k][i] / 1e6, None)));
                        packets.hits.push(h);
                    }
                    None => {
                        packets.speeds.push(None);
                        packets.hits.push(reference[i].clone());
                    }
                }
            }
            measured.push(packets);
        }
        for m in measured {
            for (i, batch) in sets.iter().enumerate() {
                let Some((mrays_s, gpu_mrays_s)) = m.speeds[i] else { continue };
                let (mismatches, flat_wrong, blind_near) = compare(sc, batch, &reference[i], &m.hits[i], m.subject);
                rows.push(Row {
                    scene: sc.name.clone(),
                    kind: sc.kind.clone(),
                    triangles: sc.tris.len(),
                    structure: m.structure.clone(),
                    family: m.family,
                    build_ms: m.build_s * 1e3,
                    memory_bytes: m.memory,
                    bytes_per_triangle: m.memory as f64 / sc.tris.len() as f64,
                    rays: batch.set,
                    ray_count: batch.rays.len() as u64,
                    hit_share: hit_share(&reference[i]),
                    mrays_s,
                    gpu_mrays_s,
                    parallel_build: subject.parallel_build(),
                    shared_triangle_test: subject.shared_test(),
                    mismatches,
                    flat_wrong,
                    blind_near,
                });
            }
        }
        pb.inc(1);
    }
    Ok(rows)
}

/// `0..n` in a random order (Fisher–Yates): each timing round visits the subjects in another
/// order.
fn shuffled(n: usize, rng: &mut gridrt_scene::rng::Rng) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        order.swap(i, rng.below(i as u64 + 1) as usize);
    }
    order
}

/// Every disagreement with the flat grid's hits (`reference`), settled by brute force (the
/// watertight test on every triangle), which says whether the flat grid or the subject is wrong:
/// (mismatches, of them where the flat grid is wrong, of them closer than the subject's blind
/// distance).
fn compare(sc: &LabScene, batch: &RayBatch, reference: &[Hit], hits: &[Hit], subject: Subject) -> (u64, u64, u64) {
    let (mut mismatches, mut flat_wrong, mut blind_near) = (0u64, 0u64, 0u64);
    for (k, (a, b)) in reference.iter().zip(hits).enumerate() {
        if agree(a, b) {
            continue;
        }
        mismatches += 1;
        let (truth, _) = gridrt_grid::brute::trace(&sc.tris, &batch.rays[k]);
        flat_wrong += u64::from(!agree(&truth, a));
        blind_near += u64::from(subject.blind_distance().is_some_and(|d| truth.t < d && b.t >= d));
        if mismatches <= 3 {
            let (name, ray, set) = (subject.name(), batch.rays[k], batch.set);
            log::warn!("{} · {name}: {set:?} ray {k} {ray:?}: flat {a:?}, this {b:?}, brute force {truth:?}", sc.name);
        }
    }
    (mismatches, flat_wrong, blind_near)
}

/// One point of the auto-resolution check: the flat grid at a multiple of the auto m.
#[derive(Clone, Debug, Serialize)]
pub struct AutoPoint {
    pub scene: String,
    pub triangles: usize,
    /// The multiple of the auto resolution (1 = the auto choice).
    pub factor: f64,
    pub resolution: [u32; 3],
    pub m: f64,
    pub cpu_ns_per_ray: f64,
}

/// Sweeps the flat grid's resolution from half to twice the auto choice (factors 2^(k/4)) and
/// times both ray sets on the CPU. The sweep's grids are built first and then timed as the
/// subjects' traces are: in rounds, every grid once a round in a shuffled order, each keeping its
/// best round, with rounds beyond `--repeat` while they fit in [`TRACE_ROUND_BUDGET_S`] (a
/// 36-triangle scene's sweep, timed grid after grid with two rounds each, had its points
/// 105–133 ns a ray apart in no order: noise, which the auto-m target then measured).
fn auto_check(sc: &LabScene, sets: &[RayBatch], args: &BenchArgs, cost: &CostModel) -> anyhow::Result<Vec<AutoPoint>> {
    let rays: Vec<Ray> = sets.iter().flat_map(|b| b.rays.iter().copied()).collect();
    let cfg = GridConfig { cost: *cost, ..GridConfig::default() };
    // The resolution the flat build's auto policy picks, without building that grid.
    let bounds = gridrt_grid::triangle_bounds_with(&sc.tris, cfg.build.parallel);
    let auto = gridrt_grid::resolution::choose(
        &sc.tris,
        &bounds,
        Resolution::Auto,
        cost,
        cfg.build.insert,
        cfg.build.parallel,
    )
    .resolution;
    let opts = TraceOptions::MAILBOX;
    let mut points = Vec::new();
    for k in -4i32..=4 {
        let f = 2f64.powf(k as f64 / 4.0);
        let res = auto.map(|a| ((a as f64 * f).round() as u32).max(1));
        let cfg = GridConfig { resolution: Some(Resolution::Explicit(res)), ..cfg };
        match structure::build(&sc.tris, &cfg) {
            Ok((g, _)) => points.push((f, res, g, f64::INFINITY)),
            // Finer grids can exceed the reference limit: that point is simply not measured.
            Err(e) => log::info!("auto check: {}: {res:?} skipped: {e}", sc.name),
        }
    }
    let mut rng = gridrt_scene::rng::Rng::new(11);
    let start = std::time::Instant::now();
    let mut round = 0;
    while another_round(round, args.repeat, start) {
        for k in shuffled(points.len(), &mut rng) {
            let (_, _, g, best) = &mut points[k];
            let (s, _) = best_of(1, || g.trace_batch(&sc.tris, &rays, opts, true));
            *best = best.min(s);
        }
        round += 1;
    }
    Ok(points
        .into_iter()
        .map(|(f, res, _, s)| AutoPoint {
            scene: sc.name.clone(),
            triangles: sc.tris.len(),
            factor: f,
            resolution: res,
            m: res.iter().map(|&r| r as f64).product::<f64>().cbrt(),
            cpu_ns_per_ray: s * 1e9 / rays.len() as f64,
        })
        .collect())
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out)?;
    let (cost, cost_note) = crate::config::calibration::active_cost_model();
    eprintln!("bench: auto resolution with {cost_note}");
    #[cfg(not(feature = "peers"))]
    eprintln!("bench: built without the `peers` feature: no bvh/obvhs rows");
    if args.dynamic {
        return dynamic::run(&args, &cost);
    }
    let scenes = pick_scenes(&args)?;
    let gpu = super::gpu_unless(args.no_gpu)?;
    let subjects = Subject::all(!args.no_peers).len();
    let steps = subjects + usize::from(!args.no_auto_check);
    let pb = progress((scenes.len() * steps) as u64, "bench");
    let (mut rows, mut auto) = (Vec::new(), Vec::new());
    for sc in &scenes {
        // The ray sets of a scene, shared by every structure and the auto-m sweep.
        pb.set_message(format!("{} · framing", sc.name));
        let sets = ray_sets(sc, &probe_grid(&sc.tris)?, if args.quick { args.rays.min(20_000) } else { args.rays });
        rows.extend(bench_scene(sc, &sets, &args, &cost, gpu.as_ref(), &pb)?);
        if !args.no_auto_check {
            pb.set_message(format!("{} · auto m sweep", sc.name));
            auto.extend(auto_check(sc, &sets, &args, &cost)?);
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    let scale = if args.no_scaling { Vec::new() } else { scaling::run(&args, &cost)? };
    let targets = targets::evaluate(&rows, &auto, &scale);

    write_rows(&args.out, "bench", &rows)?;
    write_rows(&args.out, "bench-auto-m", &auto)?;
    write_rows(&args.out, "bench-scaling", &scale)?;
    write_rows(&args.out, "bench-targets", &targets)?;
    charts(&args, &scenes, &rows, &scale)?;

    let machine = machine(gpu.as_ref());
    if args.json {
        let out = serde_json::json!({
            "date": crate::format::today(), "machine": machine, "cost_model": cost_note,
            "rays_per_set": args.rays, "repeat": args.repeat,
            "rows": rows, "auto_m": auto, "scaling": scale, "targets": targets,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "gridrt bench, {} · {machine} · {} rays per set, best of {}",
        crate::format::today(),
        args.rays,
        args.repeat
    );
    print_rows(&rows);
    if !scale.is_empty() {
        println!();
        scaling::print(&scale);
    }
    println!();
    targets::print(&targets);
    println!("\nrows, charts and targets in {}", args.out.display());
    Ok(())
}

fn charts(args: &BenchArgs, scenes: &[LabScene], rows: &[Row], scale: &[scaling::ScalePoint]) -> anyhow::Result<()> {
    let names: Vec<String> = scenes.iter().map(|s| s.name.trim_end_matches(".glb").to_string()).collect();
    let structures: Vec<String> = {
        let mut v: Vec<String> = Vec::new();
        for r in rows {
            if !v.contains(&r.structure) {
                v.push(r.structure.clone());
            }
        }
        v
    };
    type Metric = (&'static str, &'static str, bool, RaySet, fn(&Row) -> f64);
    // Build and memory stand on every set's row: they are read from the random set's.
    let metrics: [Metric; 5] = [
        ("bench-framed", "framed camera rays, Mrays/s (CPU)", true, RaySet::Framed, |r| r.mrays_s),
        ("bench-interior", "interior camera rays, Mrays/s (CPU)", true, RaySet::Interior, |r| r.mrays_s),
        ("bench-random", "random rays, Mrays/s (CPU)", true, RaySet::Random, |r| r.mrays_s),
        ("bench-build", "build ms", true, RaySet::Random, |r| r.build_ms),
        ("bench-memory", "bytes per triangle", true, RaySet::Random, |r| r.bytes_per_triangle),
    ];
    for (stem, label, log_y, set, value) in metrics {
        let rows: Vec<&Row> = rows.iter().filter(|r| r.rays == set).collect();
        if rows.is_empty() {
            continue;
        }
        let series = structures
            .iter()
            .map(|s| Series {
                label: s.clone(),
                points: scenes
                    .iter()
                    .enumerate()
                    .filter_map(|(i, sc)| {
                        rows.iter().find(|r| &r.structure == s && r.scene == sc.name).map(|r| (i as f64, value(r)))
                    })
                    .collect(),
                predicted: rows.iter().any(|r| &r.structure == s && r.family == "peer"),
            })
            .collect();
        save_chart(
            &args.out,
            stem,
            &Chart {
                title: format!("{label}: grids (filled) vs BVHs (hollow)"),
                x_label: "scene (by triangle count)".into(),
                y_label: label.into(),
                log_x: false,
                log_y,
                series,
                markers: Vec::new(),
                x_names: Some(names.clone()),
            },
        )?;
    }
    if !scale.is_empty() {
        save_chart(&args.out, "bench-scaling", &scaling::chart(scale))?;
    }
    Ok(())
}

/// The speeds table: a line per structure and scene, a CPU and a GPU column per ray set, then
/// each scene's hit shares.
fn print_rows(rows: &[Row]) {
    let sets = [RaySet::Framed, RaySet::Interior, RaySet::Random];
    let mut keys: Vec<(&str, &str)> = Vec::new();
    for r in rows {
        if !keys.contains(&(r.scene.as_str(), r.structure.as_str())) {
            keys.push((&r.scene, &r.structure));
        }
    }
    let fixed = |v: Option<f64>| v.map_or("—".into(), |v| format!("{v:.2}"));
    let table: Vec<Vec<String>> = keys
        .iter()
        .map(|&(scene, structure)| {
            let of = |set| rows.iter().find(|r| r.scene == scene && r.structure == structure && r.rays == set);
            let first = rows.iter().find(|r| r.scene == scene && r.structure == structure).expect("a row of each key");
            let (mismatches, flat_wrong) = rows
                .iter()
                .filter(|r| r.scene == scene && r.structure == structure)
                .fold((0, 0), |(m, w), r| (m + r.mismatches, w + r.flat_wrong));
            let mut line = vec![
                scene.trim_end_matches(".glb").to_string(),
                first.triangles.to_string(),
                structure.to_string(),
                format!("{:.1}", first.build_ms),
                format!("{:.0}", first.bytes_per_triangle),
            ];
            line.extend(sets.iter().map(|&s| fixed(of(s).map(|r| r.mrays_s))));
            line.extend(sets.iter().map(|&s| fixed(of(s).and_then(|r| r.gpu_mrays_s))));
            line.push(if flat_wrong > 0 {
                format!("{mismatches} ({flat_wrong} flat)")
            } else {
                mismatches.to_string()
            });
            line
        })
        .collect();
    print_table(
        &[
            "scene",
            "tris",
            "structure",
            "build ms",
            "B/tri",
            "framed",
            "interior",
            "random",
            "GPU framed",
            "GPU interior",
            "GPU random",
            "mismatch",
        ],
        &table,
    );
    println!("Mrays/s; hit share of each ray set:");
    let mut seen: Vec<(&str, RaySet)> = Vec::new();
    for r in rows.iter().filter(|r| r.structure == "flat") {
        if !seen.contains(&(r.scene.as_str(), r.rays)) {
            seen.push((&r.scene, r.rays));
            println!("  {} {}: {:.0}%", r.scene.trim_end_matches(".glb"), r.rays.name(), r.hit_share * 100.0);
        }
    }
}

#[cfg(all(test, feature = "peers"))]
mod tests {
    /// A peer's panic becomes `None` (the scene goes on without it); its result otherwise.
    #[test]
    fn a_peer_that_panics_is_left_out() {
        assert_eq!(super::peer_guard("peer", "build", || 7), Some(7));
        assert_eq!(super::peer_guard("peer", "build", || -> i32 { panic!("index out of bounds") }), None);
    }
}
