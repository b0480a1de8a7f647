//! Coherent grid traversal: packets give the hits of single rays and of brute force, bit for
//! bit, for camera images (outside and inside the scene, any tile size, widths that are not a
//! multiple of it), shadow rays from and towards a point light and incoherent rays; packets
//! really walk slice by slice where the rays are coherent.

use glam::Vec3;
use gridrt_grid::coherent::PacketOptions;
use gridrt_grid::multires::{MultiresOptions, Policy};
use gridrt_grid::trace::TraceOptions;
use gridrt_grid::{AnyGrid, BuildOptions, GridConfig, GridKind, InsertMode, structure};
use gridrt_scene::gltf_load::load_path;
use gridrt_scene::rays::{image_rays, random_rays};
use gridrt_scene::{Aabb, Camera, Hit, Ray};

use super::common::*;

/// Shadow rays between each hit and `light` (an empty ray for a miss): from the light to just
/// before the hit, as the renderer makes them (a common origin), or with `towards_light` from
/// just after the hit to the light (a common end).
pub fn shadow_rays(primary: &[Ray], hits: &[Hit], light: Vec3, diagonal: f32, towards_light: bool) -> Vec<Ray> {
    primary
        .iter()
        .zip(hits)
        .map(|(r, h)| {
            if !h.is_hit() {
                return Ray::new(Vec3::ZERO, Vec3::X, 1.0, 0.0);
            }
            let p = r.at(h.t);
            let eps = 1e-4 * diagonal / (p - light).length().max(1e-20);
            if towards_light { Ray::new(p, light - p, eps, 1.0) } else { Ray::new(light, p - light, 0.0, 1.0 - eps) }
        })
        .collect()
}

/// Cameras: the auto view, a close view, one inside the box looking along each axis sign
/// with a wide field of view, and a grazing view along the bottom face.
fn cameras(b: &Aabb) -> Vec<Camera> {
    let c = b.center();
    let e = b.extent();
    let mut v = vec![Camera::fit(b, 4.0 / 3.0)];
    v.push(Camera { eye: c + e * Vec3::new(0.3, 0.2, 0.9), target: c, up: Vec3::Y, vfov_deg: 40.0 });
    for d in [Vec3::X, -Vec3::Y, Vec3::Z, -Vec3::Z] {
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

/// Every kind at its defaults, and a deep octree-like multires grid with exact insertion (its
/// packets visit child grids four levels down, layer by layer).
fn grids(tris: &[[Vec3; 3]]) -> Vec<AnyGrid> {
    let mut grids: Vec<AnyGrid> = GridKind::ALL
        .into_iter()
        .map(|kind| structure::build(tris, &GridConfig { kind, ..GridConfig::default() }).unwrap().0)
        .collect();
    let deep = GridConfig {
        kind: GridKind::Multires,
        build: BuildOptions { insert: InsertMode::Exact, parallel: true },
        multires: MultiresOptions { policy: Policy::Octree, max_depth: 4, ..Default::default() },
        ..GridConfig::default()
    };
    grids.push(structure::build(tris, &deep).unwrap().0);
    grids
}

/// Every grid × tile size × mailbox on `rays` (an image `width` wide) against `expected`.
/// Returns the coherent packets walked.
fn check_packets(
    name: &str,
    tris: &[[Vec3; 3]],
    grids: &[AnyGrid],
    rays: &[Ray],
    width: usize,
    expected: &[Hit],
) -> u64 {
    let mut coherent = 0;
    for grid in grids {
        // Tile 3 leaves partial packets at both edges of the 37- and 24-pixel-wide images.
        for tile in [3, 8, 16] {
            for mailbox in [true, false] {
                if !mailbox && tile != 8 {
                    continue;
                }
                let packets = PacketOptions { tile, mailbox };
                let (hits, stats, ps) = grid.trace_packets(
                    tris,
                    rays,
                    width,
                    TraceOptions { mailbox, ..Default::default() },
                    packets,
                    true,
                );
                assert_same_hits(
                    &format!("{name} {} tile {tile} mailbox={mailbox}", grid.kind()),
                    rays,
                    expected,
                    &hits,
                );
                assert_eq!(stats.rays as usize, rays.len());
                if mailbox {
                    let any = TraceOptions { mailbox, ..Default::default() }.occlusion();
                    let (hits, _, _) = grid.trace_packets(tris, rays, width, any, packets, true);
                    let what = format!("{name} {} tile {tile} any hit", grid.kind());
                    assert_same_occlusion(&what, tris, rays, expected, &hits);
                }
                let tiles = (width.div_ceil(tile as usize) * (rays.len() / width).div_ceil(tile as usize)) as u64;
                assert_eq!(ps.packets + ps.single_ray_packets, tiles, "{name}: every tile is one packet");
                coherent += ps.packets;
            }
        }
    }
    coherent
}

fn check_scene_images(name: &str, tris: &[[Vec3; 3]], width: u32, height: u32) {
    let b = gridrt_grid::triangle_bounds(tris);
    let grids = grids(tris);
    let light = b.center() + b.extent() * Vec3::new(0.4, 1.5, 0.3);
    for (k, cam) in cameras(&b).iter().enumerate() {
        let rays = image_rays(cam, width, height);
        let (expected, st) = reference(tris, &rays);
        let coherent = check_packets(&format!("{name} camera {k}"), tris, &grids, &rays, width as usize, &expected);
        // The auto view's tiles are narrow: they walk as packets. Wide tiles of a small image
        // close up may all be judged too incoherent (single rays), which is right too.
        assert!(k > 0 || coherent > 0, "{name} camera {k}: no packet walked slice by slice");
        // Closest hits of shadow rays both ways: from the light and towards it.
        let towards = shadow_rays(&rays, &expected, light, b.diagonal(), true);
        let (towards_expected, _) = reference(tris, &towards);
        let what = format!("{name} camera {k} shadows towards the light");
        check_packets(&what, tris, &grids, &towards, width as usize, &towards_expected);
        let shadow = shadow_rays(&rays, &expected, light, b.diagonal(), false);
        let (shadow_expected, sst) = reference(tris, &shadow);
        let sc = check_packets(
            &format!("{name} camera {k} shadows"),
            tris,
            &grids,
            &shadow,
            width as usize,
            &shadow_expected,
        );
        // Shadow segments ending just before, at and just after their occluders (three images).
        let any = TraceOptions { mailbox: true, ..Default::default() }.occlusion();
        for end in [f32::next_down, |t| t, f32::next_up] {
            let around: Vec<Ray> = shadow
                .iter()
                .zip(&shadow_expected)
                .map(|(r, h)| if h.is_hit() { r.ending_at(end(h.t)) } else { *r })
                .collect();
            let (around_expected, _) = reference(tris, &around);
            for grid in &grids {
                let (hits, _, _) =
                    grid.trace_packets(tris, &around, width as usize, any, PacketOptions::default(), true);
                let what = format!("{name} camera {k} {} shadow segments", grid.kind());
                assert_same_occlusion(&what, tris, &around, &around_expected, &hits);
            }
        }
        println!("{name} camera {k}: {} hits, {} shadowed; {coherent} + {sc} coherent packets", st.hits, sst.hits);
    }
}

#[test]
fn packets_equal_single_rays_and_brute_force_on_procedural_scenes() {
    for (name, g) in procedural_scenes() {
        let tris = g.mesh.triangles();
        check_scene_images(&name, &tris, 37, 29);
    }
}

#[test]
fn incoherent_packets_fall_back_to_single_rays() {
    let (_, g) = procedural_scenes().remove(0);
    let tris = g.mesh.triangles();
    let b = g.mesh.bounds();
    let rays = random_rays(&b, 32 * 32, 7);
    let (expected, _) = reference(&tris, &rays);
    let grid = structure::build(&tris, &GridConfig::default()).unwrap().0;
    let (hits, _, ps) =
        grid.trace_packets(&tris, &rays, 32, TraceOptions::default(), PacketOptions { tile: 8, mailbox: true }, false);
    assert_same_hits("random rays in packets", &rays, &expected, &hits);
    assert_eq!(ps.packets + ps.single_ray_packets, 16);
    assert!(ps.single_ray_packets >= 12, "random directions: most packets are incoherent ({ps:?})");
}

/// Images whose rays include ones no triangle can be hit by (NaN, infinite or zero directions
/// and origins, empty or NaN intervals) and huge directions, alone in a packet, among good rays
/// or making up a whole packet: every packet's hits equal brute force's, and the good rays'
/// tiles still walk as packets.
#[test]
fn packets_with_hostile_rays_equal_brute_force() {
    let (name, g) = procedural_scenes().remove(0);
    let tris = g.mesh.triangles();
    let b = g.mesh.bounds();
    let (width, height) = (32u32, 24u32);
    let mut rays = image_rays(&Camera::fit(&b, 4.0 / 3.0), width, height);
    let hostile = [
        Ray::new(Vec3::NAN, Vec3::X, 0.0, f32::INFINITY),
        Ray::new(b.center(), Vec3::new(f32::NAN, 1.0, 0.0), 0.0, f32::INFINITY),
        Ray::new(b.center(), Vec3::ZERO, 0.0, f32::INFINITY),
        Ray::new(b.center(), Vec3::new(f32::INFINITY, 0.0, 0.0), 0.0, f32::INFINITY),
        Ray::new(Vec3::splat(f32::INFINITY), -Vec3::Z, 0.0, f32::INFINITY),
        Ray::new(b.center(), -Vec3::Z, 2.0, 1.0),
        Ray::new(b.center(), -Vec3::Z, f32::NAN, 1.0),
        Ray::new(b.min - b.extent(), b.extent() * 1e30, 0.0, f32::INFINITY),
    ];
    // Scattered over the image (every 7th ray) and filling its first tile.
    for (k, r) in rays.iter_mut().enumerate() {
        if k % 7 == 3 || (k % width as usize) < 8 && k / (width as usize) < 8 {
            *r = hostile[k % hostile.len()];
        }
    }
    let (expected, _) = reference(&tris, &rays);
    let coherent =
        check_packets(&format!("{name} hostile rays"), &tris, &grids(&tris), &rays, width as usize, &expected);
    assert!(coherent > 0, "{name}: no packet walked slice by slice");
}

#[test]
fn packets_equal_brute_force_on_shared_scenes() {
    let scenes = shared_scenes();
    // Each shared scene in the full matrix; a sample of three by default.
    let step = if full_matrices() { 1 } else { (scenes.len() / 3).max(1) };
    for path in scenes.iter().step_by(step) {
        let mesh = load_path(path).unwrap().0;
        let tris = mesh.triangles();
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        check_scene_images(&name, &tris, 24, 18);
    }
}

/// A stack of 80 thin parallel layers seen face on: a single ray stops at the first layer, while
/// a two-level grid's packet checks its rays' ends once per top slice, which holds dozens of
/// layers. The hierarchy's waste watch traces such packets as single rays after measuring them;
/// over one layer of large quads it keeps its packets. Hits stay those of brute force either way.
#[test]
fn wasteful_hierarchy_packets_turn_to_single_rays() {
    let stats_over = |layers: usize, n: usize| {
        let size = 16.0 / n as f32;
        let mut tris = Vec::new();
        for k in 0..layers {
            let z = k as f32 * 0.025;
            for i in 0..n {
                for j in 0..n {
                    let (x, y) = (i as f32 * size, j as f32 * size);
                    let p = |dx: f32, dy: f32| Vec3::new(x + dx * size, y + dy * size, z);
                    tris.push([p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)]);
                    tris.push([p(0.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]);
                }
            }
        }
        let (w, h) = (64, 64);
        let cam =
            Camera { eye: Vec3::new(8.3, 7.9, 30.0), target: Vec3::new(8.0, 8.0, 0.0), up: Vec3::Y, vfov_deg: 25.0 };
        let rays = image_rays(&cam, w, h);
        let (expected, _) = reference(&tris, &rays);
        assert!(expected.iter().all(|h| h.is_hit()), "the view sees the stack only");
        let grid =
            structure::build(&tris, &GridConfig { kind: GridKind::TwoLevel, ..GridConfig::default() }).unwrap().0;
        let packets = PacketOptions { tile: 8, mailbox: true };
        let (hits, _, ps) = grid.trace_packets(&tris, &rays, w as usize, TraceOptions::default(), packets, false);
        assert_same_hits(&format!("two-level packets over {layers} layers"), &rays, &expected, &hits);
        assert_eq!(ps.packets + ps.single_ray_packets, 64);
        ps
    };
    // Per band of eight packets: the first as single rays (measured), the second as a packet
    // (measured: wasteful), the rest as single rays.
    let deep = stats_over(80, 16);
    assert!(deep.packets >= 1 && deep.single_ray_packets >= 48, "80 layers: {deep:?}");
    // One layer of 4 × 4 quads: the first of each band measured as single rays, the others as
    // packets.
    let thin = stats_over(1, 4);
    assert!(thin.packets >= 48, "1 layer: {thin:?}");
}
