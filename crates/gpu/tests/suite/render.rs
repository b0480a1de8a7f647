//! The render pass: deterministic across runs, and the same hit triangle per pixel as a CPU
//! rendering of the same camera (≥ 99.9% of pixels), for every grid kind; every view renders.

use gridrt_gpu::cpu::{camera_rays, gpu_camera};
use gridrt_gpu::upload::{GpuScene, GpuStructure};
use gridrt_gpu::{RenderOptions, Renderer, View};
use gridrt_grid::trace::TraceOptions;
use gridrt_grid::{GridConfig, GridKind, Traversal, structure};
use gridrt_scene::Camera;

use super::common::gpu;

#[test]
fn default_scene_renders_deterministically_and_matches_the_cpu() {
    let Some(ctx) = gpu() else { return };
    let (mesh, _) = gridrt_scene::load_default();
    let tris = mesh.triangles();
    let bounds = mesh.bounds();
    let (w, h) = (320, 240);
    let camera = Camera::fit(&bounds, w as f32 / h as f32);
    let renderer = Renderer::new(ctx).unwrap();
    let scene = GpuScene::new(ctx, &tris).unwrap();
    let cpu_rays = camera_rays(&gpu_camera(&camera, w, h));
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    for kind in GridKind::ALL {
        let (grid, _) = structure::build(&tris, &GridConfig { kind, ..GridConfig::default() }).unwrap();
        let gs = GpuStructure::new(ctx, &grid).unwrap();
        let opts = RenderOptions {
            width: w,
            height: h,
            camera,
            view: View::Shaded,
            traversal: Traversal::AmanatidesWoo,
            mailbox: true,
            heat_max: 64.0,
        };
        let a = renderer.render(ctx, &scene, &gs, &bounds, &opts).unwrap();
        let b = renderer.render(ctx, &scene, &gs, &bounds, &opts).unwrap();
        assert_eq!(a.rgba, b.rgba, "{kind}: two renders differ");
        let (cpu_hits, _) = grid.trace_batch(
            &tris,
            &cpu_rays,
            TraceOptions { traversal: Traversal::AmanatidesWoo, mailbox: true },
            true,
        );
        let same = a.hits.iter().zip(&cpu_hits).filter(|(g, c)| g.triangle == c.triangle).count();
        let share = same as f64 / cpu_hits.len() as f64;
        let hit_pixels = cpu_hits.iter().filter(|h| h.is_hit()).count();
        println!(
            "{kind}: {:.4}% of pixels hit the same triangle on GPU and CPU ({hit_pixels} hit pixels)",
            100.0 * share
        );
        assert!(share >= 0.999, "{kind}: only {:.3}% of pixels agree", 100.0 * share);
        assert!(hit_pixels > (w * h / 10) as usize, "{kind}: the camera sees too little");
        // Not blank: several distinct colours.
        let mut colours: Vec<&[u8]> = a.rgba.chunks(4).collect();
        colours.sort();
        colours.dedup();
        assert!(colours.len() > 50, "{kind}: image looks blank ({} colours)", colours.len());
        if kind == GridKind::Flat {
            for view in View::ALL {
                let f = renderer.render(ctx, &scene, &gs, &bounds, &RenderOptions { view, ..opts }).unwrap();
                assert_eq!(f.rgba.len(), (w * h * 4) as usize);
                write_ppm(&out.join(format!("default-{}.ppm", view.name())), w, h, &f.rgba);
            }
        }
    }
}

/// A tiny PPM writer so the test can leave images to look at without an image dependency.
fn write_ppm(path: &std::path::Path, w: u32, h: u32, rgba: &[u8]) {
    let mut data = format!("P6\n{w} {h}\n255\n").into_bytes();
    for p in rgba.chunks(4) {
        data.extend_from_slice(&p[..3]);
    }
    std::fs::write(path, data).unwrap();
}
