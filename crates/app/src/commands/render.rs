//! `gridrt render SCENE -o out.png`: one GPU frame of any view, written as PNG.

use anyhow::Context;
use gridrt_gpu::{GpuSession, RenderOptions};
use gridrt_scene::Camera;

use super::build_grid;
use crate::cli::RenderArgs;

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let (mesh, report) = super::load_scene(&args.scene)?;
    let tris = mesh.triangles();
    let bounds = mesh.bounds();
    let (width, height) = args.size;
    // The frame comes back whole (pixels, hits and stats: 28 bytes a pixel); the GPU renders it
    // in tiles.
    let need = width as u64 * height as u64 * 28;
    let budget = gridrt_scene::load_budget::default_max_bytes();
    anyhow::ensure!(
        need <= budget,
        "--size {width}x{height} needs {need} bytes of frame memory, more than the budget of {budget} bytes (a quarter of memory)"
    );
    let (grid, b) = build_grid(&tris, &args.grid.config()?)?;
    let aspect = width as f32 / height as f32;
    let camera = match args.camera.as_str() {
        "auto" => Camera::fit(&bounds, aspect),
        "framed" => crate::lab::views::framed_camera(&tris, &bounds, &grid, aspect),
        "interior" => crate::lab::views::interior_camera(&tris, &bounds, &grid),
        s => Camera::parse(s).map_err(|e| anyhow::anyhow!("--camera: {e}"))?,
    };
    let ctx = super::gpu_context()?;
    let gpu = GpuSession::new(&ctx, &tris, bounds)?;
    let gs = gpu.upload(&grid)?;
    let opts = RenderOptions {
        width,
        height,
        camera,
        view: args.view,
        traversal: args.traversal,
        mailbox: !args.no_mailbox,
        heat_max: args.heat_max,
    };
    // Warm-up on a small frame: pipeline compilation stays out of the timing.
    gpu.render(&gs, &RenderOptions { width: 64, height: 48, ..opts })?;
    let start = std::time::Instant::now();
    let frame = gpu.render(&gs, &opts)?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    image::save_buffer(&args.output, &frame.rgba, width, height, image::ExtendedColorType::Rgba8)
        .with_context(|| format!("writing {}", args.output.display()))?;
    let n = frame.stats.len() as f64;
    let cells: f64 = frame.stats.iter().map(|s| s.cells as f64).sum::<f64>() / n;
    let tests: f64 = frame.stats.iter().map(|s| s.tests as f64).sum::<f64>() / n;
    println!(
        "{} ({} triangles), {} grid, {} view, {width}x{height}",
        report.source,
        tris.len(),
        grid.kind(),
        args.view.name()
    );
    println!(
        "frame: {ms:.1} ms ({:.2} Mrays/s primary), {cells:.2} cells and {tests:.2} tests per primary ray; build {:.1} ms",
        n / ms / 1e3,
        b.times.total()
    );
    if args.view.is_heatmap() {
        println!(
            "colour scale: 0 black, {:.0} blue, {:.0} cyan, {:.0} green, {:.0} yellow, {:.0} red, >= {:.0} white",
            args.heat_max / 6.0,
            args.heat_max * 2.0 / 6.0,
            args.heat_max * 3.0 / 6.0,
            args.heat_max * 4.0 / 6.0,
            args.heat_max * 5.0 / 6.0,
            args.heat_max
        );
    }
    println!("wrote {}", args.output.display());
    Ok(())
}
