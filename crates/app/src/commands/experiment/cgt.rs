//! `gridrt experiment cgt`: coherent grid traversal (Wald et al. 2006; the survey's §2.2)
//! against single rays on the CPU, on every scene, for the flat, macrocell and two-level grids
//! (the last walks its child grids layer by layer inside each top slice): the
//! packets' speed-up on primary rays and on shadow rays to the point light, by packet size and
//! by image resolution (square images, a camera the model fills). It tests the paper's two
//! claims, "frustum packets more than 10× faster than single rays" and "cost sublinear in the
//! screen resolution" (the log–log slope of frame time against pixels below 1), and checks on
//! every image that packets give single rays' hits bit for bit.

use gridrt_gpu::render::{RenderOptions, shade_params};
use gridrt_grid::trace::TraceOptions;
use gridrt_grid::{AnyGrid, GridConfig, GridKind, PacketOptions, structure};
use gridrt_scene::Ray;
use serde::Serialize;

use crate::cli::ExperimentArgs;
use crate::lab::frame::shadow_rays_from_hits;
use crate::lab::report::{Chart, Series, print_table, progress, save_chart, write_rows};
use crate::lab::scenes::{LabScene, default_scenes, every_scene, procedural_scenes};
use crate::lab::sweep::{best_of, machine};
use crate::lab::views::{framed_camera, probe_grid};

/// The grids measured (every grid walks packets; multires walks them as the two-level grid does).
const GRIDS: [GridKind; 3] = [GridKind::Flat, GridKind::Macrocell, GridKind::TwoLevel];
/// The paper's claim of packets over single rays.
const PAPER_SPEED_UP: f64 = 10.0;

/// One image traced one way: single rays (`tile` None) or `tile`×`tile` packets.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub scene: String,
    pub triangles: usize,
    pub grid: &'static str,
    /// Image edge in pixels (square images).
    pub size: u32,
    /// "primary" or "shadow".
    pub rays: &'static str,
    pub tile: Option<u32>,
    pub ms: f64,
    pub mrays_s: f64,
    /// Single rays' time over this row's (1 for single rays).
    pub speed_up: f64,
    pub cells_per_ray: f64,
    pub tests_per_ray: f64,
    pub packets: u64,
    pub single_ray_packets: u64,
    /// Rays whose hit differs in any bit from single rays' (must be 0).
    pub mismatches: u64,
}

/// The image sizes (edges) and, at the middle one, the packet sizes.
fn plan(quick: bool) -> (Vec<u32>, u32, Vec<u32>) {
    if quick { (vec![96, 192], 192, vec![4, 8]) } else { (vec![512, 1024, 2048], 1024, vec![4, 8, 16]) }
}

pub fn run(args: &ExperimentArgs) -> anyhow::Result<()> {
    let dir = if args.procedural { None } else { args.scenes.clone().or_else(default_scenes) };
    let scenes = match dir {
        Some(dir) => every_scene(&dir, args.quick)?,
        None => procedural_scenes(args.quick),
    };
    let (sizes, main_size, tiles) = plan(args.quick);
    let repeat = if args.quick { 1 } else { 2 };
    let pb = progress((scenes.len() * GRIDS.len() * sizes.len()) as u64, "cgt");
    let mut rows = Vec::new();
    for sc in &scenes {
        let camera = framed_camera(&sc.tris, &sc.bounds, &probe_grid(&sc.tris)?, 1.0);
        for kind in GRIDS {
            pb.set_message(format!("{} · {kind}", sc.name));
            let (grid, _) = structure::build(&sc.tris, &GridConfig { kind, ..GridConfig::default() })?;
            for &size in &sizes {
                let opts = RenderOptions::new(camera, size, size);
                let packet_tiles: &[u32] = if size == main_size { &tiles } else { &[8] };
                rows.extend(measure_image(sc, &grid, &opts, packet_tiles, repeat));
                pb.inc(1);
            }
        }
    }
    pb.finish_and_clear();
    write_rows(&args.out, "cgt", &rows)?;
    charts(args, &scenes, &rows, main_size, &sizes)?;
    print(&rows, main_size, &sizes);
    println!("wrote cgt.csv, .json and cgt-*.svg/.png to {}", args.out.display());
    Ok(())
}

/// Primary rays of one image and their shadow rays (occlusion queries), traced as single rays
/// and in packets of each tile size; each packet row's hits checked against single rays'.
fn measure_image(sc: &LabScene, grid: &AnyGrid, opts: &RenderOptions, tiles: &[u32], repeat: usize) -> Vec<Row> {
    let topts = TraceOptions::MAILBOX;
    let primary = gridrt_gpu::cpu::camera_rays(&gridrt_gpu::cpu::gpu_camera(&opts.camera, opts.width, opts.height));
    let shade = shade_params(&sc.bounds, opts);
    let width = opts.width as usize;
    let mut rows = Vec::new();
    let mut shadow = Vec::new();
    for which in ["primary", "shadow"] {
        let rays: &[Ray] = if which == "primary" { &primary } else { &shadow };
        // Shadow rays are occlusion queries (any hit), as the renderer traces them: their
        // packets must agree with single rays on hit or miss.
        let topts = if which == "primary" { topts } else { topts.occlusion() };
        let same = |a: &gridrt_scene::Hit, b: &gridrt_scene::Hit| {
            if which == "primary" { a.same_bits(b) } else { a.is_hit() == b.is_hit() }
        };
        let (s, (hits, stats)) = best_of(repeat, || grid.trace_batch(&sc.tris, rays, topts, true));
        let row = |tile, ms: f64, stats: gridrt_grid::BatchStats| Row {
            scene: sc.name.clone(),
            triangles: sc.tris.len(),
            grid: grid.kind().name(),
            size: opts.width,
            rays: which,
            tile,
            ms,
            mrays_s: rays.len() as f64 / ms / 1e3,
            speed_up: s * 1e3 / ms,
            cells_per_ray: stats.mean_cells(),
            tests_per_ray: stats.mean_tests(),
            packets: 0,
            single_ray_packets: 0,
            mismatches: 0,
        };
        rows.push(row(None, s * 1e3, stats));
        for &tile in tiles {
            let popts = PacketOptions { tile, mailbox: true };
            let (p, (phits, pstats, packets)) =
                best_of(repeat, || grid.trace_packets(&sc.tris, rays, width, topts, popts, true));
            let mismatches = hits.iter().zip(&phits).filter(|(a, b)| !same(a, b)).count() as u64;
            rows.push(Row {
                packets: packets.packets,
                single_ray_packets: packets.single_ray_packets,
                mismatches,
                ..row(Some(tile), p * 1e3, pstats)
            });
        }
        if which == "primary" {
            shadow_rays_from_hits(&shade, &primary, &hits, &mut shadow);
        }
    }
    rows
}

/// Log–log slope of time against pixels over the sizes (least squares); `None` with fewer
/// than two sizes.
fn slope(points: &[(f64, f64)]) -> Option<f64> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

fn short(name: &str) -> String {
    name.trim_end_matches(".glb").trim_end_matches(".gltf").to_string()
}

/// Frame ms against pixels for one scene, grid, ray kind and tile (None: single rays).
fn by_size<'a>(rows: &'a [Row], scene: &str, grid: &str, rays: &str, tile: Option<u32>) -> Vec<&'a Row> {
    rows.iter().filter(|r| r.scene == scene && r.grid == grid && r.rays == rays && r.tile == tile).collect()
}

fn charts(args: &ExperimentArgs, scenes: &[LabScene], rows: &[Row], main: u32, sizes: &[u32]) -> anyhow::Result<()> {
    let names: Vec<String> = scenes.iter().map(|s| short(&s.name)).collect();
    // Speed-up of 8×8 packets by scene at the main size.
    let series = GRIDS
        .iter()
        .flat_map(|k| ["primary", "shadow"].map(|w| (k.name(), w)))
        .map(|(grid, which)| Series {
            label: format!("{grid}, {which}"),
            points: scenes
                .iter()
                .enumerate()
                .filter_map(|(i, sc)| {
                    let r = rows.iter().find(|r| {
                        r.scene == sc.name && r.grid == grid && r.rays == which && r.tile == Some(8) && r.size == main
                    })?;
                    Some((i as f64, r.speed_up))
                })
                .collect(),
            predicted: which == "shadow",
        })
        .collect();
    let title = format!("8×8 packets over single rays at {main}² (the paper: > {PAPER_SPEED_UP}×)");
    let chart = Chart {
        title,
        x_label: "scene (by triangle count)".into(),
        y_label: "speed-up".into(),
        log_x: false,
        log_y: false,
        series,
        markers: vec![],
        x_names: Some(names),
    };
    save_chart(&args.out, "cgt-speedup", &chart)?;
    // Speed-up against packet size, flat grid, primary rays, at the main size.
    let series = scenes
        .iter()
        .map(|sc| Series {
            label: short(&sc.name),
            points: rows
                .iter()
                .filter(|r| r.scene == sc.name && r.grid == "flat" && r.rays == "primary" && r.size == main)
                .filter_map(|r| Some((r.tile? as f64, r.speed_up)))
                .collect(),
            predicted: false,
        })
        .collect();
    let chart = Chart::log_log(
        &format!("flat grid, primary rays at {main}²: speed-up against packet edge"),
        "packet edge (pixels)",
        "speed-up over single rays",
        series,
    );
    save_chart(&args.out, "cgt-tile", &chart)?;
    // Frame time against pixels, flat grid, primary rays: packets solid, single rays dashed.
    if sizes.len() >= 2 {
        let series = scenes
            .iter()
            .flat_map(|sc| [(sc, Some(8)), (sc, None)])
            .map(|(sc, tile)| Series {
                label: format!("{}{}", short(&sc.name), if tile.is_some() { ", 8×8" } else { ", single" }),
                points: by_size(rows, &sc.name, "flat", "primary", tile)
                    .iter()
                    .map(|r| ((r.size as f64).powi(2), r.ms))
                    .collect(),
                predicted: tile.is_none(),
            })
            .collect();
        let chart = Chart::log_log(
            "flat grid, primary rays: frame ms against pixels (slope < 1: sublinear)",
            "pixels",
            "ms",
            series,
        );
        save_chart(&args.out, "cgt-resolution", &chart)?;
    }
    Ok(())
}

fn print(rows: &[Row], main: u32, sizes: &[u32]) {
    println!("Coherent grid traversal against single rays, CPU, {}:", machine(None));
    let mut scenes: Vec<&str> = Vec::new();
    for r in rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    let mut table = Vec::new();
    let mut best = (0.0f64, String::new());
    // The best speed-up of any packet size at the main size.
    let best_any = rows
        .iter()
        .filter(|r| r.rays == "primary" && r.size == main && r.tile.is_some())
        .max_by(|a, b| a.speed_up.total_cmp(&b.speed_up));
    let (mut slopes_packets, mut slopes_single) = (Vec::new(), Vec::new());
    for &scene in &scenes {
        for kind in GRIDS {
            let grid = kind.name();
            let at = |which: &str, tile: Option<u32>| {
                rows.iter()
                    .find(|r| r.scene == scene && r.grid == grid && r.rays == which && r.tile == tile && r.size == main)
            };
            let (Some(p1), Some(s1)) = (at("primary", None), at("shadow", None)) else { continue };
            let speed =
                |which, tile| at(which, Some(tile)).map_or("—".into(), |r: &Row| format!("{:.2}", r.speed_up));
            if let Some(r) = at("primary", Some(8))
                && r.speed_up > best.0
            {
                best = (r.speed_up, format!("{} {grid}", short(scene)));
            }
            let fit = |tile| {
                slope(
                    &by_size(rows, scene, grid, "primary", tile)
                        .iter()
                        .map(|r| ((r.size as f64).powi(2), r.ms))
                        .collect::<Vec<_>>(),
                )
            };
            let (sp, ss) = (fit(Some(8)), fit(None));
            slopes_packets.extend(sp);
            slopes_single.extend(ss);
            let mismatches: u64 =
                rows.iter().filter(|r| r.scene == scene && r.grid == grid).map(|r| r.mismatches).sum();
            table.push(vec![
                short(scene),
                grid.to_string(),
                format!("{:.2}", p1.mrays_s),
                speed("primary", 4),
                speed("primary", 8),
                speed("primary", 16),
                format!("{:.2}", s1.mrays_s),
                speed("shadow", 8),
                sp.map_or("—".into(), |v| format!("{v:.2}")),
                ss.map_or("—".into(), |v| format!("{v:.2}")),
                mismatches.to_string(),
            ]);
        }
    }
    print_table(
        &[
            "scene",
            "grid",
            "single Mrays/s",
            "4×4",
            "8×8",
            "16×16",
            "shadow single",
            "shadow 8×8",
            "slope 8×8",
            "slope single",
            "mismatches",
        ],
        &table,
    );
    println!(
        "speed-ups over single rays at {main}²; slopes of log ms against log pixels over {sizes:?}² (8×8 packets and single rays)"
    );
    let range = |v: &[f64]| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if v.is_empty() { "—".to_string() } else { format!("{lo:.2}–{hi:.2}") }
    };
    println!(
        "paper's \"more than {PAPER_SPEED_UP}×\": best 8×8 primary speed-up here {:.2} ({}): {}",
        best.0,
        best.1,
        if best.0 > PAPER_SPEED_UP { "agrees" } else { "does not reach it" }
    );
    if let Some(r) = best_any {
        let t = r.tile.unwrap_or(0);
        println!(
            "  best of any packet size: {:.2} ({} {}, {t}×{t}): {}",
            r.speed_up,
            short(&r.scene),
            r.grid,
            if r.speed_up > PAPER_SPEED_UP { "agrees" } else { "does not reach it" }
        );
    }
    let sublinear = slopes_packets.iter().filter(|&&s| s < 1.0).count();
    println!(
        "paper's \"sublinear in resolution\": 8×8 packet slopes {} ({sublinear} of {} below 1), single rays {}",
        range(&slopes_packets),
        slopes_packets.len(),
        range(&slopes_single)
    );
    let bad: u64 = rows.iter().map(|r| r.mismatches).sum();
    println!(
        "hits: {}",
        if bad == 0 {
            "packets equal single rays bit for bit on every image".to_string()
        } else {
            format!("{bad} rays DIFFER from single rays")
        }
    );
}
