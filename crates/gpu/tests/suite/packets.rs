//! The GPU's packet kernels (coherent grid traversal, `shaders/shared/coherent.wgsl`) give the
//! single-ray kernels' hits bit for bit: camera images from outside, close, inside the scene
//! and grazing, image widths that are not a multiple of the packet edge, shadow rays towards
//! the light, on every grid kind (the hierarchies and proximity clouds fall back to their
//! single-ray kernels), and in the renderer, whose tiles start anywhere in a row.

use glam::Vec3;
use gridrt_gpu::cpu::{camera_rays, gpu_camera, shadow_ray};
use gridrt_gpu::render::shade_params;
use gridrt_gpu::trace::tile_quantum;
use gridrt_gpu::{FrameTarget, GpuSession, RenderOptions, View};
use gridrt_grid::{GridConfig, GridKind, TraceOptions, structure};
use gridrt_scene::procedural::{SceneKind, generate};
use gridrt_scene::{Aabb, Camera, Hit, Ray};

use super::common::{default_scene, gpu, hostile_scenes, read_texture};

/// The auto view, a close view, two views from inside the box with a wide field of view, and
/// a grazing view along the bottom face.
fn cameras(b: &Aabb) -> Vec<Camera> {
    let (c, e) = (b.center(), b.extent());
    let mut v = vec![Camera::fit(b, 4.0 / 3.0)];
    v.push(Camera { eye: c + e * Vec3::new(0.3, 0.2, 0.9), target: c, up: Vec3::Y, vfov_deg: 40.0 });
    for d in [Vec3::X, -Vec3::Z] {
        v.push(Camera { eye: c + e * 0.05, target: c + d, up: Vec3::Y, vfov_deg: 110.0 });
    }
    v.push(Camera {
        eye: Vec3::new(b.min.x - e.x, b.min.y + e.y * 1e-3, c.z),
        target: Vec3::new(b.max.x, b.min.y, c.z),
        up: Vec3::Y,
        vfov_deg: 30.0,
    });
    v
}

fn differing(a: &[Hit], b: &[Hit]) -> usize {
    a.iter().zip(b).filter(|(x, y)| !x.same_bits(y)).count()
}

#[test]
fn packet_kernels_equal_single_ray_kernels_bit_for_bit() {
    let Some(ctx) = gpu() else { return };
    let mut walked = 0;
    for kind in [SceneKind::Sphereflake, SceneKind::TeapotInStadium, SceneKind::Mountain] {
        let mesh = generate(kind, 2, 3).mesh;
        let tris = mesh.triangles();
        let b = mesh.bounds();
        let gpu = GpuSession::new(ctx, &tris, b).unwrap();
        for grid_kind in GridKind::ALL {
            let (grid, _) = structure::build(&tris, &GridConfig { kind: grid_kind, ..GridConfig::default() }).unwrap();
            let gs = gpu.upload(&grid).unwrap();
            for (ci, cam) in cameras(&b).iter().enumerate() {
                // 45 and 37 pixels wide: partial packets at the right edge and the bottom.
                let (w, h) = if ci % 2 == 0 { (45, 34) } else { (37, 29) };
                let opts = RenderOptions::new(*cam, w, h);
                let rays = camera_rays(&gpu_camera(cam, w, h));
                for mailbox in [true, false] {
                    let (single, single_stats) =
                        gpu.trace(&gs, &rays, TraceOptions { mailbox, ..Default::default() }).unwrap();
                    let (packets, stats) =
                        gpu.trace_image(&gs, &rays, w, TraceOptions { mailbox, ..Default::default() }).unwrap();
                    let name = format!("{kind:?} {grid_kind} camera {ci} mailbox {mailbox}");
                    assert_eq!(differing(&single, &packets), 0, "{name}: primary rays");
                    assert_eq!(stats.len(), rays.len());
                    // The packet kernel really ran where there is one: a packet's rays count the
                    // cells of its slices, not the cells of their own walks.
                    let counted_apart = single_stats.iter().zip(&stats).any(|(a, b)| a.cells != b.cells);
                    let has_kernel = matches!(grid_kind, GridKind::Flat | GridKind::Macrocell);
                    assert_eq!(counted_apart, has_kernel, "{name}: which kernel ran");
                    if !mailbox {
                        continue;
                    }
                    // Rays of a scaled walk (directions of 2^20) make their packets incoherent:
                    // traced alone, with the single-ray kernel's hits and counts.
                    if has_kernel {
                        let scale = |r: &Ray| Ray::new(r.o(), r.d() * 1048576.0, r.tmin, r.tmax);
                        let big: Vec<Ray> = rays.iter().map(scale).collect();
                        let (s, s_stats) = gpu.trace(&gs, &big, TraceOptions::MAILBOX).unwrap();
                        let (p, p_stats) = gpu.trace_image(&gs, &big, w, TraceOptions::MAILBOX).unwrap();
                        assert_eq!(differing(&s, &p), 0, "{name}: scaled rays");
                        let alone = s_stats.iter().zip(&p_stats).all(|(a, b)| a.cells == b.cells);
                        assert!(alone, "{name}: scaled rays walked as a packet");
                    }
                    // Shadow rays from the light to the hits, as the renderer makes them (a common origin).
                    let shade = shade_params(&b, &opts);
                    let shadow: Vec<_> = rays.iter().zip(&single).map(|(r, h)| shadow_ray(&shade, r, h)).collect();
                    let (s1, _) = gpu.trace(&gs, &shadow, TraceOptions::MAILBOX).unwrap();
                    let (s2, _) = gpu.trace_image(&gs, &shadow, w, TraceOptions::MAILBOX).unwrap();
                    assert_eq!(differing(&s1, &s2), 0, "{name}: shadow rays");
                    // Occlusion queries (the renderer's shadow pass): hit or miss as the closest
                    // query, in both kernels, also on segments ending at and around the hits.
                    let mut segments = shadow.clone();
                    for end in [f32::next_down, |t| t, f32::next_up] {
                        segments.extend(
                            shadow.iter().zip(&s1).map(|(r, h)| if h.is_hit() { r.ending_at(end(h.t)) } else { *r }),
                        );
                    }
                    let (closest, _) = gpu.trace(&gs, &segments, TraceOptions::MAILBOX).unwrap();
                    let any = TraceOptions::MAILBOX.occlusion();
                    let (a1, _) = gpu.trace(&gs, &segments, any).unwrap();
                    let (a2, _) = gpu.trace_image(&gs, &segments, w, any).unwrap();
                    for (what, got) in [("single", &a1), ("packets", &a2)] {
                        let wrong = closest.iter().zip(got.iter()).filter(|(c, a)| c.is_hit() != a.is_hit()).count();
                        assert_eq!(wrong, 0, "{name}: occlusion queries ({what}) disagree with closest hits");
                    }
                    walked += usize::from(single.iter().any(|h| h.is_hit()));
                }
            }
        }
    }
    assert!(walked > 20, "too few images with hits: {walked}");
}

/// The packet kernels on the hostile scenes (tiny, huge, triangles on cell walls): primary rays
/// of every camera, the single-ray kernels' hits bit for bit.
#[test]
fn packet_kernels_equal_single_ray_kernels_on_hostile_scenes() {
    let Some(ctx) = gpu() else { return };
    for (name, tris) in hostile_scenes() {
        let b = Aabb::from_points(tris.iter().flatten());
        let gpu = GpuSession::new(ctx, &tris, b).unwrap();
        for grid_kind in [GridKind::Flat, GridKind::Macrocell] {
            let (grid, _) = structure::build(&tris, &GridConfig { kind: grid_kind, ..GridConfig::default() }).unwrap();
            let gs = gpu.upload(&grid).unwrap();
            for (ci, cam) in cameras(&b).iter().enumerate() {
                let (w, h) = (45, 34);
                let rays = camera_rays(&gpu_camera(cam, w, h));
                let (single, _) = gpu.trace(&gs, &rays, TraceOptions::MAILBOX).unwrap();
                let (packets, _) = gpu.trace_image(&gs, &rays, w, TraceOptions::MAILBOX).unwrap();
                assert_eq!(differing(&single, &packets), 0, "{name} {grid_kind} camera {ci}");
            }
        }
    }
}

/// The renderer with packets: the same hits as without, whole frames and tiles that start in
/// the middle of a row (odd sizes), every view.
#[test]
fn rendering_with_packets_gives_the_same_frames() {
    let Some(ctx) = gpu() else { return };
    let (tris, gpu) = default_scene(ctx);
    // 128 × 4 bytes per row meets the texture copy's 256-byte alignment.
    let (w, h) = (128, 75);
    for kind in [GridKind::Flat, GridKind::Macrocell, GridKind::Multires] {
        let (grid, _) = structure::build(&tris, &GridConfig { kind, ..GridConfig::default() }).unwrap();
        let gs = gpu.upload(&grid).unwrap();
        let single = RenderOptions::fit(&gpu.bounds, w, h);
        let packets = RenderOptions { packets: true, ..single };
        let a = gpu.render(&gs, &single).unwrap();
        let b = gpu.render(&gs, &packets).unwrap();
        assert_eq!(differing(&a.hits, &b.hits), 0, "{kind}: primary hits");
        assert_eq!(a.rgba, b.rgba, "{kind}: shaded pixels (shadow rays included)");
        for view in [View::Depth, View::HeatmapTests] {
            let f = gpu.render(&gs, &RenderOptions { view, ..packets }).unwrap();
            assert_eq!(differing(&a.hits, &f.hits), 0, "{kind} {view:?}");
        }
        // Tiles of an odd size into a display target: each starts at another column.
        let renderer = gpu.renderer().unwrap();
        let target = FrameTarget::new(ctx, w, h, true).unwrap();
        let count = 3 * tile_quantum(ctx) + 5;
        let mut first = 0;
        while first < w * h {
            let n = count.min(w * h - first);
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            renderer.encode_tile(ctx, &mut enc, &gpu.source(&gs), &packets, &target, first..first + n).unwrap();
            ctx.queue.submit([enc.finish()]);
            first += n;
        }
        let texels = read_texture(ctx, &target, ctx.device.create_command_encoder(&Default::default()));
        assert_eq!(texels, a.rgba, "{kind}: tiles of {count} pixels in packets");
    }
    ctx.check_device().unwrap();
}
