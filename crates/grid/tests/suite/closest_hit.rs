//! Closest hits through every grid kind equal brute force exactly (same triangle, same t bits)
//! for every kind × traversal × insertion × mailbox, with serial and parallel builds
//! bit-identical, on procedural scenes and on ../shared/scenes when present; rays from inside
//! closed meshes never escape.

use glam::Vec3;
use gridrt_grid::trace::TraceOptions;
use gridrt_grid::{AnyGrid, BuildOptions, GridConfig, GridKind, InsertMode, Query, Resolution, Traversal, structure};
use gridrt_scene::Ray;
use gridrt_scene::gltf_load::load_path;
use gridrt_scene::rays::inside_rays;

use super::common::*;

/// Rays per scene in the full matrix (`GRIDRT_FULL_MATRICES=1`); a tenth by default.
const RAYS: usize = 100_000;

/// Builds every kind × insertion serially and in parallel (must be identical), then compares
/// every traversal × mailbox against the reference. `all_builds`: also trace through the
/// parallel builds (identical by the check, so optional for big scenes). `inserts`: the
/// insertion modes to build with.
pub fn check_scene(name: &str, tris: &[[Vec3; 3]], rays: &[Ray], all_builds: bool, inserts: &[InsertMode]) {
    let (expected, ref_stats) = reference(tris, rays);
    println!("{name}: {} triangles, {} rays, {} hits", tris.len(), rays.len(), ref_stats.hits);
    assert!(ref_stats.hits as usize > rays.len() / 20, "{name}: suspiciously few hits ({})", ref_stats.hits);
    for kind in GridKind::ALL {
        for &insert in inserts {
            let mut grids = Vec::new();
            for parallel in [false, true] {
                let cfg = GridConfig { kind, build: BuildOptions { insert, parallel }, ..GridConfig::default() };
                let (grid, report) = structure::build(tris, &cfg).unwrap();
                if !parallel {
                    let s = &report.stats;
                    println!(
                        "  {kind} {insert:?}: top {:?}, {} nodes, {} refs, {} bytes",
                        s.resolution, s.nodes, s.refs, s.memory_bytes
                    );
                }
                grids.push((parallel, grid));
            }
            assert!(grids[0].1 == grids[1].1, "{name} {kind} {insert:?}: parallel build differs from serial");
            for (parallel, grid) in &grids {
                if *parallel && !all_builds {
                    continue;
                }
                for traversal in Traversal::EXACT {
                    for mailbox in [false, true] {
                        let opts = TraceOptions { traversal, mailbox, ..Default::default() };
                        let (hits, stats) = grid.trace_batch(tris, rays, opts, true);
                        assert_same_hits(
                            &format!("{name} {kind} {insert:?} parallel={parallel} {traversal} mailbox={mailbox}"),
                            rays,
                            &expected,
                            &hits,
                        );
                        if mailbox {
                            let (any, _) = grid.trace_batch(tris, rays, opts.occlusion(), true);
                            assert_same_occlusion(
                                &format!("{name} {kind} {insert:?} parallel={parallel} {traversal} any hit"),
                                tris,
                                rays,
                                &expected,
                                &any,
                            );
                        }
                        if !parallel && mailbox {
                            println!(
                                "    {traversal:>4} + mailbox: {:.2} cells/ray, {:.2} tests/ray",
                                stats.mean_cells(),
                                stats.mean_tests()
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn every_grid_equals_brute_force_on_procedural_scenes() {
    for (name, g) in procedural_scenes() {
        let tris = g.mesh.triangles();
        let rays = mixed_rays(&g.mesh, &g.inside_points, matrix_rays(RAYS), 11);
        check_scene(&name, &tris, &rays, true, &InsertMode::ALL);
    }
}

#[test]
fn every_grid_equals_brute_force_on_shared_scenes() {
    // Sampled (the default): each scene builds with one insertion mode, alternating, so the
    // scenes between them cover both; in full (CI) every scene builds with both.
    for (i, path) in shared_scenes().iter().enumerate() {
        let (mesh, _) = load_path(path).unwrap();
        let tris = mesh.triangles();
        let rays = mixed_rays(&mesh, &[], matrix_rays(RAYS), 5);
        let inserts = if full_matrices() { &InsertMode::ALL[..] } else { &InsertMode::ALL[i % 2..i % 2 + 1] };
        check_scene(&path.file_name().unwrap().to_string_lossy(), &tris, &rays, false, inserts);
    }
}

#[test]
fn occlusion_queries_equal_brute_force_on_segments_ending_at_hits() {
    // Segments ending one ulp before, at and one ulp after each closest hit: any hit must be
    // found exactly when the closest one lies in the segment.
    for (name, g) in procedural_scenes() {
        let tris = g.mesh.triangles();
        let rays = mixed_rays(&g.mesh, &g.inside_points, matrix_rays(30_000), 17);
        let (closest, _) = reference(&tris, &rays);
        let segments = segments_around_hits(&rays, &closest);
        let (expected, st) = reference(&tris, &segments);
        assert!(st.hits > 0 && (st.hits as usize) < segments.len(), "{name}: segments both hit and miss");
        for kind in GridKind::ALL {
            for insert in InsertMode::ALL {
                let cfg = GridConfig { kind, build: BuildOptions { insert, parallel: true }, ..GridConfig::default() };
                let (grid, _) = structure::build(&tris, &cfg).unwrap();
                for traversal in Traversal::EXACT {
                    for mailbox in [false, true] {
                        let opts = TraceOptions { traversal, mailbox, query: Query::Any, ..Default::default() };
                        let (any, _) = grid.trace_batch(&tris, &segments, opts, true);
                        let what = format!("{name} {kind} {insert:?} {traversal} mailbox={mailbox}");
                        assert_same_occlusion(&what, &tris, &segments, &expected, &any);
                    }
                }
            }
        }
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
            rays.extend(inside_rays(&g.mesh, *p, matrix_rays(20_000) / g.inside_points.len() + 40, i as u64));
        }
        for kind in GridKind::ALL {
            for res in [None, Some(Resolution::Cubic(3)), Some(Resolution::Cubic(200))] {
                for insert in InsertMode::ALL {
                    let cfg = GridConfig {
                        kind,
                        resolution: res,
                        build: BuildOptions { insert, parallel: true },
                        ..GridConfig::default()
                    };
                    let (grid, _) = structure::build(&tris, &cfg).unwrap();
                    for traversal in Traversal::EXACT {
                        for mailbox in [false, true] {
                            let opts = TraceOptions { traversal, mailbox, ..Default::default() };
                            let (hits, stats) = grid.trace_batch(&tris, &rays, opts, true);
                            let escaped = hits.iter().filter(|h| !h.is_hit()).count();
                            assert_eq!(
                                escaped,
                                0,
                                "{name} {kind} {res:?} {insert:?} {traversal} mailbox={mailbox}: {escaped} of {} rays escaped",
                                rays.len()
                            );
                            assert_eq!(stats.hits as usize, rays.len());
                        }
                    }
                }
            }
        }
        // The reference is watertight too.
        let (hits, _) = reference(&tris, &rays);
        assert!(hits.iter().all(|h| h.is_hit()), "{name}: brute force lets rays escape");
    }
}

#[test]
fn interleaved_walks_equal_single_rays_and_brute_force() {
    // The interleaved paths run by themselves (whatever the grid's size and the rays'
    // coherence): hits and stats equal the single-ray walks' on every ray, for the flat, the
    // macrocell and the proximity grid, both queries and insertions, with and without the mailbox, and on batches
    // shorter than the slots (rays in flight end in every order: misses of the grid, rays no
    // triangle can be hit by, clipped segments).
    use gridrt_grid::trace::interleaved::{SLOTS, trace_grid_interleaved};
    let mut scenes = procedural_scenes();
    scenes.push((
        "particles, 100k".into(),
        gridrt_scene::procedural::generate(gridrt_scene::procedural::SceneKind::Particles, 100_000, 5),
    ));
    for (name, g) in scenes {
        let tris = g.mesh.triangles();
        let mut rays = mixed_rays(&g.mesh, &g.inside_points, matrix_rays(40_000), 23);
        rays.push(Ray::new(Vec3::splat(1e6), Vec3::X, 0.0, f32::INFINITY));
        rays.push(Ray::new(Vec3::ZERO, Vec3::ZERO, 0.0, f32::INFINITY));
        rays.push(Ray::new(Vec3::splat(f32::NAN), Vec3::X, 0.0, 1.0));
        let (expected, _) = reference(&tris, &rays);
        for kind in [GridKind::Flat, GridKind::Macrocell, GridKind::Proximity] {
            for insert in InsertMode::ALL {
                let cfg = GridConfig { kind, build: BuildOptions { insert, parallel: true }, ..GridConfig::default() };
                let (grid, _) = structure::build(&tris, &cfg).unwrap();
                for query in [Query::Closest, Query::Any] {
                    for mailbox in [false, true] {
                        let opts =
                            TraceOptions { traversal: Traversal::AmanatidesWoo, mailbox, query, ..Default::default() };
                        let what = format!("{name} {kind} {insert:?} {query:?} mailbox={mailbox}");
                        let (single, per_ray): (Vec<_>, Vec<_>) =
                            rays.iter().map(|r| grid.trace(&tris, r, opts)).unzip();
                        for len in [rays.len(), SLOTS - 3, 1] {
                            let mut hits = vec![gridrt_scene::Hit::MISS; len];
                            let (rs, hs) = (&rays[..len], &mut hits[..]);
                            let stats = match &grid {
                                AnyGrid::Flat(f) => trace_grid_interleaved(f, &tris, rs, hs, opts),
                                AnyGrid::Macrocell(m) => trace_grid_interleaved(m, &tris, rs, hs, opts),
                                AnyGrid::Proximity(p) => trace_grid_interleaved(p, &tris, rs, hs, opts),
                                _ => unreachable!(),
                            };
                            let mut want = gridrt_grid::BatchStats::default();
                            for (s, h) in per_ray[..len].iter().zip(&single[..len]) {
                                want.add(*s, h.is_hit());
                            }
                            assert_eq!(stats, want, "{what}, {len} rays: stats");
                            assert!(
                                hits.iter().zip(&single).all(|(a, b)| a.same_bits(b)),
                                "{what}, {len} rays: interleaved hits differ from single rays"
                            );
                        }
                        if query == Query::Closest {
                            assert_same_hits(&what, &rays, &expected, &single);
                        }
                    }
                }
            }
        }
    }
}

/// Cell slabs (`gridrt_grid::cell_plane`) skip cells, never hits: with a slab on every cell
/// that has one (`CellPlanes::On`), the flat and macrocell grids equal brute force for every
/// traversal × insertion × mailbox, closest and any hit (segments ending one ulp before, at and
/// after each hit: the slab check of the cell a segment ends in), single rays and interleaved
/// walks alike; each slab holds its cell's triangles; and the slabs spare tests.
#[test]
fn cell_slabs_skip_tests_never_hits() {
    use gridrt_grid::cell_plane::{CellPlane, CellPlanes};
    use gridrt_grid::trace::interleaved::trace_grid_interleaved;
    let mut spared = 0.0f64;
    for (name, g) in procedural_scenes() {
        let tris = g.mesh.triangles();
        let rays = mixed_rays(&g.mesh, &g.inside_points, matrix_rays(20_000), 29);
        let (expected, _) = reference(&tris, &rays);
        let segments = segments_around_hits(&rays, &expected);
        let (expected_any, _) = reference(&tris, &segments);
        for kind in [GridKind::Flat, GridKind::Macrocell] {
            for insert in InsertMode::ALL {
                let build = BuildOptions { insert, parallel: true };
                let with = GridConfig { kind, build, cell_planes: CellPlanes::On, ..GridConfig::default() };
                let without = GridConfig { cell_planes: CellPlanes::Off, ..with };
                let (grid, _) = structure::build(&tris, &with).unwrap();
                let (plain, _) = structure::build(&tris, &without).unwrap();
                let fine = match &grid {
                    AnyGrid::Flat(f) => f,
                    AnyGrid::Macrocell(m) => &m.fine,
                    _ => unreachable!(),
                };
                assert_eq!(fine.planes.len() + 1, fine.ref_start.len(), "{name} {kind} {insert:?}: a slab per cell");
                // Every corner of every triangle of a cell lies in its slab (grid space, f64).
                let (min, inv) = (fine.geom.min.as_dvec3(), fine.geom.inv_cell.as_dvec3());
                for (j, p) in fine.planes.iter().enumerate().filter(|(_, p)| **p != CellPlane::NONE) {
                    let n = glam::Vec3::from_array(p.n).as_dvec3();
                    for &t in &fine.refs[fine.ref_start[j] as usize..fine.ref_start[j + 1] as usize] {
                        for c in tris[t as usize] {
                            let d = n.dot((c.as_dvec3() - min) * inv);
                            assert!(d >= p.lo as f64 && d <= p.hi as f64, "{name} {kind} {insert:?}: cell {j}");
                        }
                    }
                }
                for traversal in Traversal::EXACT {
                    for mailbox in [false, true] {
                        let opts = TraceOptions { traversal, mailbox, ..Default::default() };
                        let what = format!("{name} {kind} {insert:?} {traversal} mailbox={mailbox}, slabs");
                        let (hits, stats) = grid.trace_batch(&tris, &rays, opts, true);
                        assert_same_hits(&what, &rays, &expected, &hits);
                        let (any, _) = grid.trace_batch(&tris, &segments, opts.occlusion(), true);
                        assert_same_occlusion(&what, &tris, &segments, &expected_any, &any);
                        if traversal == Traversal::AmanatidesWoo {
                            let (_, base) = plain.trace_batch(&tris, &rays, opts, true);
                            assert!(stats.tests <= base.tests, "{what}: more tests with slabs");
                            spared = spared.max(1.0 - stats.tests as f64 / base.tests.max(1) as f64);
                            let mut inter = vec![gridrt_scene::Hit::MISS; rays.len()];
                            let istats = match &grid {
                                AnyGrid::Flat(f) => trace_grid_interleaved(f, &tris, &rays, &mut inter, opts),
                                AnyGrid::Macrocell(m) => trace_grid_interleaved(m, &tris, &rays, &mut inter, opts),
                                _ => unreachable!(),
                            };
                            assert_eq!(istats, stats, "{what}: interleaved stats");
                            assert!(inter.iter().zip(&hits).all(|(a, b)| a.same_bits(b)), "{what}: interleaved hits");
                        }
                    }
                }
            }
        }
    }
    assert!(spared > 0.2, "the slabs spared at most {:.0}% of the tests", spared * 100.0);
}
