//! Degenerate inputs for every grid kind: a scene flat in one axis, a single triangle, a
//! million triangles in one cell, triangles far outside the rest. Correct hits, bounded memory,
//! no panic.

use glam::Vec3;
use gridrt_grid::trace::TraceOptions;
use gridrt_grid::{BuildOptions, GridConfig, GridKind, InsertMode, Traversal, structure};
use gridrt_scene::procedural;
use gridrt_scene::rays::random_rays;
use gridrt_scene::rng::Rng;
use gridrt_scene::{Aabb, Camera, Mesh, Ray};

use super::common::{assert_same_hits, reference};

fn rays_for(tris: &[[Vec3; 3]], count: usize) -> Vec<Ray> {
    let b = Aabb::from_points(tris.iter().flatten());
    let mut r = random_rays(&b, count / 2, 3);
    r.extend(gridrt_scene::rays::camera_rays(&Camera::fit(&b, 1.0), count - count / 2));
    r
}

/// Every kind and traversal reproduces brute force; memory stays under `max_bytes_per_tri`.
fn check(name: &str, tris: &[[Vec3; 3]], rays: usize, max_bytes_per_tri: f64) {
    let rays = rays_for(tris, rays);
    let (expected, _) = reference(tris, &rays);
    for kind in GridKind::ALL {
        for insert in InsertMode::ALL {
            let cfg = GridConfig { kind, build: BuildOptions { insert, parallel: true }, ..GridConfig::default() };
            let (grid, report) = structure::build(tris, &cfg).unwrap_or_else(|e| panic!("{name} {kind}: {e}"));
            let per_tri = report.stats.memory_bytes as f64 / tris.len() as f64;
            println!(
                "{name} {kind} {insert:?}: {:?} top, {} nodes, {per_tri:.0} bytes/triangle",
                report.stats.resolution, report.stats.nodes
            );
            assert!(per_tri <= max_bytes_per_tri, "{name} {kind} {insert:?}: {per_tri} bytes per triangle");
            for traversal in Traversal::EXACT {
                let (hits, _) = grid.trace_batch(
                    tris,
                    &rays,
                    TraceOptions { traversal, mailbox: true, ..Default::default() },
                    true,
                );
                assert_same_hits(&format!("{name} {kind} {insert:?} {traversal}"), &rays, &expected, &hits);
            }
        }
    }
}

#[test]
fn scene_flat_in_one_axis() {
    let mut m = procedural::fractal_mountain(5, 1);
    for p in &mut m.positions {
        p.y = 0.25;
    }
    check("flat-z", &m.triangles(), 20_000, 2000.0);
}

#[test]
fn single_triangle() {
    let t = [[Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)]];
    check("one", &t, 20_000, 1e6);
    let sliver = [[Vec3::new(-5.0, 0.0, 0.0), Vec3::new(5.0, 1e-4, 0.0), Vec3::new(5.0, 0.0, 2e-4)]];
    check("one-sliver", &sliver, 20_000, 1e6);
}

#[test]
fn a_million_triangles_in_one_cell() {
    // A million tiny triangles packed into a 1e-3 box, inside a 10-unit room (12 triangles).
    let mut rng = Rng::new(9);
    let mut mesh = procedural::box_mesh(Vec3::splat(-5.0), Vec3::splat(5.0));
    let mut cloud = Mesh::default();
    for i in 0..1_000_000u32 {
        let c = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 1e-3;
        for _ in 0..3 {
            cloud.positions.push(c + rng.unit_vector() * 1e-5);
        }
        cloud.indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    mesh.append(&cloud);
    check("million-in-one-cell", &mesh.triangles(), 1500, 400.0);
}

#[test]
fn triangles_far_outside_the_rest() {
    let mut m = procedural::sphereflake(1, 1).mesh;
    m.append(&procedural::box_mesh(Vec3::splat(1e5), Vec3::splat(1e5 + 1.0)));
    m.append(&procedural::box_mesh(Vec3::splat(-3e4), Vec3::new(-3e4 + 0.1, -3e4 + 0.1, -3e4 + 50.0)));
    check("far-outliers", &m.triangles(), 20_000, 5000.0);
}

/// Collinear triangles (the third corner at the midpoint of the others, as lattice scenes and
/// scanned meshes have them): hit at their ends, where exact insertion once left them out (its
/// plane axis, whose normal is rounding noise for such a triangle, took the first corner's
/// projection for the whole triangle). Every kind, both insertions, resolutions that put the
/// ends on and off cell walls, rays aimed at the ends and midpoints from lattice points.
#[test]
fn collinear_triangles_are_found_at_their_ends() {
    let mut rng = Rng::new(2143);
    let mut lattice = |n: u64| Vec3::new(rng.below(n) as f32, rng.below(n) as f32, rng.below(n) as f32);
    // The case the fuzz found, inside a 16-cube fixed by two tiny triangles at its corners.
    let mut tris = vec![[Vec3::new(6.0, 1.0, 9.0), Vec3::new(15.0, 6.0, 14.0), Vec3::new(10.5, 3.5, 11.5)]];
    for c in [Vec3::ZERO, Vec3::splat(16.0)] {
        tris.push([c, c + Vec3::new(0.01, 0.0, 0.0), c + Vec3::new(0.0, 0.01, 0.0)]);
    }
    for _ in 0..60 {
        let (a, b) = (lattice(17), lattice(17));
        if a != b {
            tris.push([a, b, (a + b) * 0.5]);
        }
    }
    let mut rays = vec![Ray::new(Vec3::new(13.0, 2.0, 8.0), Vec3::new(1.0, 2.0, 3.0), 0.0, 16.0)];
    for t in tris.clone() {
        for target in [t[0], t[1], t[2]] {
            for _ in 0..8 {
                let o = lattice(17);
                if o != target {
                    rays.push(Ray::new(o, target - o, 0.0, 2.0));
                }
            }
        }
    }
    let (expected, _) = reference(&tris, &rays);
    assert!(expected[0].is_hit(), "the fuzz's ray hits the end of its collinear triangle");
    for kind in GridKind::ALL {
        for insert in InsertMode::ALL {
            for m in [17, 31, 32, 33, 47] {
                let cfg = GridConfig {
                    kind,
                    build: BuildOptions { insert, parallel: true },
                    resolution: Some(gridrt_grid::Resolution::Cubic(m)),
                    ..GridConfig::default()
                };
                let (grid, _) = structure::build(&tris, &cfg).unwrap();
                for traversal in Traversal::EXACT {
                    let opts = TraceOptions { traversal, mailbox: true, ..Default::default() };
                    let (hits, _) = grid.trace_batch(&tris, &rays, opts, true);
                    assert_same_hits(
                        &format!("collinear {kind} {insert:?} m={m} {traversal}"),
                        &rays,
                        &expected,
                        &hits,
                    );
                }
            }
        }
    }
}
