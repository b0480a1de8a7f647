//! `gridrt render SCENE -o out.png`: one frame of any view, written as PNG. On the GPU the
//! render kernels draw it; on the CPU the same rays (the kernels' CPU ports) are traced on all
//! threads, in coherent packets by default, and shaded by the CPU port of the shade kernel.
//! Optionally the primary rays and hits, and a JSON summary.

use anyhow::Context;
use gridrt_gpu::{GpuSession, RenderOptions};
use gridrt_grid::{AnyGrid, PacketStats};
use serde_json::json;

use super::build_grid;
use crate::cli::{Device, RenderArgs};
use crate::lab::frame::{Rendered, cpu_frame};

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let (mesh, report) = super::load_scene(&args.scene)?;
    let tris = mesh.triangles();
    let bounds = mesh.bounds();
    let (width, height) = args.size;
    // The frame comes back whole (pixels, hits and stats: 28 bytes a pixel, and the CPU's
    // rays: 32 more).
    let need = width as u64 * height as u64 * 60;
    let budget = gridrt_scene::load_budget::default_max_bytes();
    anyhow::ensure!(
        need <= budget,
        "--size {width}x{height} needs {need} bytes of frame memory, more than the budget of {budget} bytes (a quarter of memory)"
    );
    let (grid, b) = build_grid(&tris, &args.grid.config()?)?;
    let aspect = width as f32 / height as f32;
    let camera = crate::lab::views::camera(args.camera, &tris, &bounds, &grid, aspect);
    let opts = RenderOptions {
        width,
        height,
        camera,
        view: args.view,
        traversal: args.traversal,
        mailbox: !args.no_mailbox,
        heat_max: args.heat_max,
        packets: args.packets.on(),
    };
    // The CPU's rays (the GPU makes its own): traced on the CPU, or written with --rays-out.
    let primary = (args.backend == Device::Cpu || args.rays_out.is_some())
        .then(|| gridrt_gpu::cpu::camera_rays(&gridrt_gpu::cpu::gpu_camera(&camera, width, height)));
    let tile = args.packets.tile;
    let (frame, adapter) = match args.backend {
        Device::Gpu => {
            anyhow::ensure!(
                !opts.packets || tile == gridrt_gpu::Kernel::PACKET_EDGE,
                "the GPU's packet kernels trace {0}x{0} packets: --tile {tile} needs --backend cpu",
                gridrt_gpu::Kernel::PACKET_EDGE,
            );
            let ctx = super::gpu_context(Some(super::CpuRoute::BackendCpu))?;
            let gpu = super::on_device(GpuSession::new(&ctx, &tris, bounds))?;
            let gs = super::on_device(gpu.upload(&grid))?;
            // Warm-up on a small frame: pipeline compilation stays out of the timing.
            gpu.render(&gs, &RenderOptions { width: 64, height: 48, ..opts })?;
            let frame = gpu.render(&gs, &opts)?;
            let n = frame.stats.len().max(1) as f64;
            let rendered = Rendered {
                cells_per_ray: frame.stats.iter().map(|s| s.cells as f64).sum::<f64>() / n,
                tests_per_ray: frame.stats.iter().map(|s| s.tests as f64).sum::<f64>() / n,
                rgba: frame.rgba,
                hits: frame.hits,
                primary_ms: frame.times.primary_ms,
                shadow_ms: frame.times.shadow_ms,
                // On the GPU every 8×8 tile of each pass is one packet workgroup (an incoherent
                // one traces its rays singly; the kernel does not count them apart).
                packets: PacketStats { packets: gpu_packets(&grid, &opts), single_ray_packets: 0 },
            };
            (rendered, Some(ctx.adapter_name()))
        }
        Device::Cpu => {
            anyhow::ensure!(
                !(args.view.is_heatmap() && opts.packets),
                "the heatmap views need per-ray counts, which packets do not keep: add --packets off"
            );
            let primary = primary.as_deref().expect("the CPU's rays");
            (cpu_frame(&grid, &tris, &bounds, &opts, primary, args.packets.options(opts.mailbox)), None)
        }
    };
    image::save_buffer(&args.output, &frame.rgba, width, height, image::ExtendedColorType::Rgba8)
        .with_context(|| format!("writing {}", args.output.display()))?;
    if let Some(path) = &args.hits_out {
        gridrt_scene::rays::write_hits(path, &frame.hits).with_context(|| format!("writing {}", path.display()))?;
    }
    if let (Some(path), Some(primary)) = (&args.rays_out, &primary) {
        gridrt_scene::rays::write_rays(path, primary).with_context(|| format!("writing {}", path.display()))?;
    }
    let rays = frame.hits.len();
    let hits = frame.hits.iter().filter(|h| h.is_hit()).count();
    let backend = match args.backend {
        Device::Cpu => "cpu",
        Device::Gpu => "gpu",
    };
    if args.json {
        let out = json!({
            "scene": report.source, "triangles": tris.len(), "grid": grid.kind().name(), "backend": backend,
            "adapter": adapter, "view": args.view.name(), "width": width, "height": height, "rays": rays, "hits": hits,
            "primary_ms": frame.primary_ms, "shadow_ms": frame.shadow_ms, "build_ms": b.times.total(),
            "packets": frame.packets.packets, "single_ray_packets": frame.packets.single_ray_packets,
            "tile": if frame.packets.packets > 0 { Some(tile) } else { None },
            "cells_per_ray": frame.cells_per_ray, "tests_per_ray": frame.tests_per_ray,
            "output": args.output,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "{} ({} triangles), {} grid, {} view, {width}x{height} on the {backend}",
        report.source,
        tris.len(),
        grid.kind(),
        args.view.name()
    );
    let packets = match (args.backend, frame.packets.packets + frame.packets.single_ray_packets) {
        (Device::Gpu, 0) if opts.packets => {
            format!("; packets: none (the {} grid's kernel traces single rays)", grid.kind())
        }
        (Device::Gpu, 0) => String::new(),
        (Device::Gpu, n) => format!("; 8x8 packets: {n} workgroups (incoherent ones trace single rays)"),
        (_, 0) if opts.packets => format!("; packets: none (the {} grid traces single rays)", grid.kind()),
        (_, 0) => String::new(),
        (_, _) => format!(
            "; {0}x{0} packets: {1} walked slice by slice, {2} incoherent (single rays)",
            tile, frame.packets.packets, frame.packets.single_ray_packets
        ),
    };
    let mrays = |ms: f64| rays as f64 / ms / 1e3;
    let shadow = frame.shadow_ms.map(|s| format!(", shadow {s:.1} ms")).unwrap_or_default();
    println!(
        "primary {:.1} ms ({:.2} Mrays/s){shadow}, {:.2} cells and {:.2} tests per primary ray{packets}; build {:.1} ms",
        frame.primary_ms,
        mrays(frame.primary_ms),
        frame.cells_per_ray,
        frame.tests_per_ray,
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

/// The packet workgroups of a GPU frame: an 8×8 tile per pass (primary, and shadow for the shaded
/// view) where the structure has a packet kernel.
fn gpu_packets(grid: &AnyGrid, o: &RenderOptions) -> u64 {
    let kernel = gridrt_gpu::Kernel::for_kind(grid.kind());
    if !o.packets || kernel.packet_file().is_none() {
        return 0;
    }
    let edge = gridrt_gpu::Kernel::PACKET_EDGE;
    let passes = if o.view == gridrt_gpu::View::Shaded { 2 } else { 1 };
    o.width.div_ceil(edge) as u64 * o.height.div_ceil(edge) as u64 * passes
}
