//! Closest hits through the flat grid equal brute force exactly (same triangle, same t bits)
//! for every traversal × insertion × mailbox × serial/parallel build, on procedural scenes and
//! on ../shared/scenes when present; rays from inside closed meshes never escape.

use glam::Vec3;
use gridrt_grid::trace::{TraceOptions, trace_batch, trace_flat};
use gridrt_grid::{BuildOptions, CostModel, FlatGrid, InsertMode, Resolution, Traversal, build_flat};
use gridrt_scene::Ray;
use gridrt_scene::gltf_load::load_path;
use gridrt_scene::rays::inside_rays;

use super::common::*;

const RAYS: usize = 100_000;

/// Builds every (insertion, serial/parallel) grid, checks serial == parallel bit for bit, and
/// compares every traversal × mailbox against the reference. `all_builds`: also trace through
/// the parallel grids (identical by the check above, so optional for big scenes).
fn check_scene(name: &str, tris: &[[Vec3; 3]], rays: &[Ray], all_builds: bool) {
    let (expected, ref_stats) = reference(tris, rays);
    println!("{name}: {} triangles, {} rays, {} hits", tris.len(), rays.len(), ref_stats.hits);
    assert!(ref_stats.hits as usize > rays.len() / 20, "{name}: suspiciously few hits ({})", ref_stats.hits);
    for insert in [InsertMode::BoundingBox, InsertMode::Exact] {
        let mut grids: Vec<(bool, FlatGrid)> = Vec::new();
        for parallel in [false, true] {
            let (grid, choice, _) =
                build_flat(tris, Resolution::Auto, &CostModel::default(), BuildOptions { insert, parallel }).unwrap();
            println!("  {insert:?} parallel={parallel}: resolution {:?}, refs {}", choice.resolution, grid.refs.len());
            grids.push((parallel, grid));
        }
        assert!(grids[0].1 == grids[1].1, "{name} {insert:?}: parallel build differs from serial");
        for (parallel, grid) in &grids {
            if *parallel && !all_builds {
                continue;
            }
            for traversal in Traversal::EXACT {
                for mailbox in [false, true] {
                    let opts = TraceOptions { traversal, mailbox };
                    let (hits, stats) = trace_batch(rays, true, |r| trace_flat(grid, tris, r, opts));
                    assert_same_hits(
                        &format!("{name} {insert:?} parallel={parallel} {traversal} mailbox={mailbox}"),
                        rays,
                        &expected,
                        &hits,
                    );
                    println!(
                        "    {traversal:>4} mailbox={mailbox:<5}: {:.2} cells/ray, {:.2} tests/ray",
                        stats.mean_cells(),
                        stats.mean_tests()
                    );
                }
            }
        }
    }
}

#[test]
fn flat_grid_equals_brute_force_on_procedural_scenes() {
    for (name, g) in procedural_scenes() {
        let tris = g.mesh.triangles();
        let rays = mixed_rays(&g.mesh, &g.inside_points, RAYS, 11);
        check_scene(&name, &tris, &rays, true);
    }
}

#[test]
fn flat_grid_equals_brute_force_on_shared_scenes() {
    let scenes = shared_scenes();
    if scenes.is_empty() {
        println!("../shared/scenes not present: nothing to do (procedural scenes are tested separately)");
        return;
    }
    for path in scenes {
        let (mesh, _) = load_path(&path).unwrap();
        let tris = mesh.triangles();
        let rays = mixed_rays(&mesh, &[], RAYS, 5);
        check_scene(&path.file_name().unwrap().to_string_lossy(), &tris, &rays, false);
    }
}

#[test]
fn rays_from_inside_closed_meshes_never_escape() {
    // Tessellated spheres (one and a sphereflake) and the knot tube: every ray from an inside
    // point, aimed exactly at vertices, edge midpoints and edge points, must hit something.
    let mut scenes = vec![("icosphere", gridrt_scene::procedural::sphereflake(0, 3))];
    scenes.push(("sphereflake", gridrt_scene::procedural::sphereflake(2, 1)));
    scenes.push(("knot", gridrt_scene::procedural::teapot_in_stadium(1)));
    for (name, g) in scenes {
        let tris = g.mesh.triangles();
        let mut rays = Vec::new();
        for (i, p) in g.inside_points.iter().enumerate() {
            rays.extend(inside_rays(&g.mesh, *p, 20_000 / g.inside_points.len() + 40, i as u64));
        }
        for res in [Resolution::Auto, Resolution::Cubic(3), Resolution::Cubic(200)] {
            for insert in [InsertMode::BoundingBox, InsertMode::Exact] {
                let (grid, _, _) =
                    build_flat(&tris, res, &CostModel::default(), BuildOptions { insert, parallel: true }).unwrap();
                for traversal in Traversal::EXACT {
                    for mailbox in [false, true] {
                        let opts = TraceOptions { traversal, mailbox };
                        let (hits, stats) = trace_batch(&rays, true, |r| trace_flat(&grid, &tris, r, opts));
                        let escaped = hits.iter().filter(|h| !h.is_hit()).count();
                        assert_eq!(
                            escaped,
                            0,
                            "{name} {res:?} {insert:?} {traversal} mailbox={mailbox}: {escaped} of {} rays escaped",
                            rays.len()
                        );
                        assert_eq!(stats.hits as usize, rays.len());
                    }
                }
            }
        }
        // The reference is watertight too.
        let (hits, _) = reference(&tris, &rays);
        assert!(hits.iter().all(|h| h.is_hit()), "{name}: brute force lets rays escape");
    }
}
