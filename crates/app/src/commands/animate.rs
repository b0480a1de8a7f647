//! `gridrt animate SCENE`: the survey's dynamic-scene loop. Every frame poses the scene at its
//! clip time, rebuilds the chosen grid from scratch and traces one primary and one shadow ray
//! per pixel (CPU on all threads, or the GPU kernels), timing pose, build and trace apart.
//! Optional PNG frames, a timeline (CSV, JSON, chart) and a JSON summary on stdout.

use std::path::Path;
use std::time::Instant;

use anyhow::Context as _;
use gridrt_gpu::{GpuSession, RenderOptions};
use serde::Serialize;

use super::build_grid;
use crate::cli::{AnimateArgs, Device};
use crate::lab::animation::FixedView;
use crate::lab::report::{Chart, Series, progress, save_chart, write_rows};
use gridrt_scene::Player;

/// One frame of the timeline.
#[derive(Clone, Debug, Serialize)]
pub struct FrameRow {
    pub frame: u32,
    /// Clip time of the pose, seconds.
    pub time: f64,
    pub pose_ms: f64,
    /// The whole rebuild, resolution choice included.
    pub build_ms: f64,
    /// Primary and shadow rays (GPU: upload of the triangles and the grid included).
    pub trace_ms: f64,
    /// Of `trace_ms`, the primary rays' trace and the shadow rays' (their generation from the
    /// primary hits included; on the GPU each pass's own time).
    pub primary_ms: f64,
    pub shadow_ms: f64,
    pub total_ms: f64,
    pub grid_bytes: u64,
    pub primary_hits: u64,
    /// Shadow rays that hit something (CPU backend only).
    pub shadowed: Option<u64>,
}

#[derive(Debug, Serialize)]
struct Summary {
    frames: usize,
    mean_pose_ms: f64,
    mean_build_ms: f64,
    mean_trace_ms: f64,
    mean_total_ms: f64,
    /// Frames per second of the whole loop (pose + build + trace).
    frames_per_second: f64,
}

#[derive(Debug, Serialize)]
struct Timeline<'a> {
    scene: &'a str,
    triangles: usize,
    animation: usize,
    animation_name: Option<&'a str>,
    grid: String,
    backend: &'static str,
    /// Primary and shadow rays in coherent packets.
    packets: bool,
    width: u32,
    height: u32,
    fps: f64,
    frames: &'a [FrameRow],
    summary: Summary,
}

pub fn run(args: AnimateArgs) -> anyhow::Result<()> {
    let loaded = super::load_rigged(&args.scene)?;
    let source = loaded.report.source.clone();
    let first = super::clip_time(&loaded.rig, &args.scene)?;
    let mut player = Player::new(loaded, first.clip);
    let clip = player.rig.clips()[first.clip].clone();
    let frames = args.frames.unwrap_or_else(|| ((clip.duration() * args.fps).round() as u32).max(1));
    let mut cfg = args.grid.config()?;
    cfg.cell_planes = cfg.cell_planes.for_tracing(!args.packets.on() && args.backend != Device::Gpu);
    let (width, height) = args.size;
    let bounds = player.clip_bounds(16)?;
    let view = FixedView::new(&bounds, width, height);
    let packets_on = args.packets.on();
    let opts = RenderOptions { packets: packets_on, ..view.opts };
    let (shade, primary, trace_opts) = (&view.shade, &view.primary, view.trace_options());
    let packets = args.packets.options(trace_opts.mailbox);
    let ctx = match args.backend {
        Device::Gpu => Some(super::gpu_context(Some(super::CpuRoute::BackendCpu))?),
        Device::Cpu => None,
    };
    for dir in [&args.frames_dir, &args.out].into_iter().flatten() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    // One session for every frame (its pipelines compile once, on a warm-up frame outside the
    // timing); each frame uploads its posed triangles and its grid.
    let mut gpu = match &ctx {
        Some(ctx) => {
            let (grid, _) = build_grid(&player.tris, &cfg)?;
            let gpu = super::on_device(GpuSession::new(ctx, &player.tris, bounds))?;
            gpu.render(&super::on_device(gpu.upload(&grid))?, &RenderOptions { width: 64, height: 48, ..opts })?;
            Some(gpu)
        }
        None => None,
    };

    let pb = progress(frames as u64, "frames");
    let mut rows = Vec::with_capacity(frames as usize);
    let mut shadow = Vec::new();
    // Each frame's grid is built into the previous frame's arrays (no fresh memory per frame).
    let mut scratch = gridrt_grid::BuildScratch::default();
    for k in 0..frames {
        let time = player.frame_time(first.seconds, k, args.fps);
        let start = Instant::now();
        player.pose(time)?;
        let posed = Instant::now();
        let (grid, _) = gridrt_grid::structure::build_reusing(&player.tris, &cfg, &mut scratch)
            .with_context(|| format!("building the {} grid", cfg.kind))?;
        let built = Instant::now();
        let tris = &player.tris;
        // Hits, shadowed rays, the end of tracing, and the image when it is wanted (the CPU
        // shades after the timing).
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        let (primary_hits, shadowed, traced, passes, rgba) = match &mut gpu {
            Some(gpu) => {
                super::on_device(gpu.set_triangles(tris))?;
                let frame = gpu.render(&super::on_device(gpu.upload(&grid))?, &opts)?;
                let traced = Instant::now();
                let hits = frame.hits.iter().filter(|h| h.is_hit()).count() as u64;
                let passes = (frame.times.primary_ms, frame.times.shadow_ms.unwrap_or(0.0));
                (hits, None, traced, passes, Some(frame.rgba))
            }
            None => {
                let trace = |rays, o| crate::lab::frame::trace_frame(&grid, tris, rays, width as usize, o, packets);
                let (hits, st, _) = trace(primary, trace_opts);
                let primary_done = Instant::now();
                crate::lab::frame::shadow_rays_from_hits(shade, primary, &hits, &mut shadow);
                // Shadow rays as occlusion queries (any hit).
                let (shadow_hits, sst, _) = trace(&shadow, trace_opts.occlusion());
                let traced = Instant::now();
                let rgba = args
                    .frames_dir
                    .as_ref()
                    .map(|_| crate::lab::frame::shade_pixels(shade, tris, primary, &hits, None, &shadow_hits));
                (st.hits, Some(sst.hits), traced, (ms(built, primary_done), ms(primary_done, traced)), rgba)
            }
        };
        rows.push(FrameRow {
            frame: k,
            time,
            pose_ms: ms(start, posed),
            build_ms: ms(posed, built),
            trace_ms: ms(built, traced),
            primary_ms: passes.0,
            shadow_ms: passes.1,
            total_ms: ms(start, traced),
            grid_bytes: grid.memory_bytes(),
            primary_hits,
            shadowed,
        });
        scratch.recycle(grid);
        if let (Some(dir), Some(rgba)) = (&args.frames_dir, rgba) {
            let path = dir.join(format!("frame_{k:05}.png"));
            image::save_buffer(&path, &rgba, width, height, image::ExtendedColorType::Rgba8)
                .with_context(|| format!("writing {}", path.display()))?;
        }
        pb.inc(1);
    }
    pb.finish_and_clear();

    let n = rows.len() as f64;
    let mean = |f: fn(&FrameRow) -> f64| rows.iter().map(f).sum::<f64>() / n;
    let summary = Summary {
        frames: rows.len(),
        mean_pose_ms: mean(|r| r.pose_ms),
        mean_build_ms: mean(|r| r.build_ms),
        mean_trace_ms: mean(|r| r.trace_ms),
        mean_total_ms: mean(|r| r.total_ms),
        frames_per_second: 1e3 / mean(|r| r.total_ms),
    };
    if let Some(out) = &args.out {
        write_rows(out, "timeline", &rows)?;
        save_chart(out, "timeline", &timeline_chart(&source, cfg.kind.name(), &rows))?;
    }
    let backend = match args.backend {
        Device::Cpu => "cpu",
        Device::Gpu => "gpu",
    };
    if args.json {
        let t = Timeline {
            scene: &source,
            triangles: player.tris.len(),
            animation: clip.index,
            animation_name: clip.name.as_deref(),
            grid: cfg.kind.name().into(),
            backend,
            packets: packets_on,
            width,
            height,
            fps: args.fps,
            frames: &rows,
            summary,
        };
        println!("{}", serde_json::to_string_pretty(&t)?);
        return Ok(());
    }
    let name = clip.name.as_deref().map(|n| format!(" {n:?}")).unwrap_or_default();
    println!(
        "{source} ({} triangles), animation {}{name}: {} frames at {} fps, {} grid rebuilt every frame, {width}x{height} primary + shadow rays on the {backend}{}",
        player.tris.len(),
        clip.index,
        rows.len(),
        args.fps,
        cfg.kind,
        if packets_on { " in packets" } else { "" }
    );
    println!(
        "per frame: pose {:.2} ms, build {:.2} ms, trace {:.2} ms, total {:.2} ms ({:.1} frames/s)",
        summary.mean_pose_ms,
        summary.mean_build_ms,
        summary.mean_trace_ms,
        summary.mean_total_ms,
        summary.frames_per_second
    );
    if let Some(dir) = &args.frames_dir {
        println!("frames: {}", dir.join("frame_NNNNN.png").display());
    }
    if let Some(out) = &args.out {
        println!("timeline: {}", out.join("timeline.{csv,json,svg,png}").display());
    }
    Ok(())
}

fn timeline_chart(source: &str, grid: &str, rows: &[FrameRow]) -> Chart {
    let series = |label: &str, f: fn(&FrameRow) -> f64| Series {
        label: label.into(),
        points: rows.iter().map(|r| (r.frame as f64, f(r))).collect(),
        predicted: false,
    };
    let file = Path::new(source).file_name().map_or(source.into(), |f| f.to_string_lossy().into_owned());
    Chart {
        title: format!("{file}: {grid} grid rebuilt every frame"),
        x_label: "frame".into(),
        y_label: "ms".into(),
        log_x: false,
        log_y: false,
        series: vec![
            series("pose", |r| r.pose_ms),
            series("build", |r| r.build_ms),
            series("trace (primary + shadow)", |r| r.trace_ms),
            series("primary rays", |r| r.primary_ms),
            series("shadow rays", |r| r.shadow_ms),
            series("total", |r| r.total_ms),
        ],
        markers: vec![],
        x_names: None,
    }
}
