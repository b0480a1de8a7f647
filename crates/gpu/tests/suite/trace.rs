//! GPU trace kernels vs the CPU structures: for every grid kind × traversal with a kernel, on
//! 100k rays per procedural scene (and shared scenes when present): the same triangle for every
//! ray except near-ties (another triangle within 1e-5 relative t, counted and reported), t
//! within 1e-5 relative (to max(t, the scene's extent / |d|): a hit at tiny t carries the
//! rounding of the scene's coordinates), and the same cells-visited count except where a hit
//! lies on a cell boundary and its t rounds differently (counted and reported).

use glam::Vec3;
use gridrt_gpu::shaders::HitFloat;
use gridrt_gpu::trace::Tracer;
use gridrt_gpu::upload::{GpuScene, GpuStructure};
use gridrt_grid::cell_plane::CellPlanes;
use gridrt_grid::multires::{MultiresOptions, Policy};
use gridrt_grid::ray::PreparedRay;
use gridrt_grid::trace::TraceOptions;
use gridrt_grid::triangle::intersect;
use gridrt_grid::{AnyGrid, GridConfig, GridKind, Resolution, Traversal, hierarchy, structure};
use gridrt_scene::procedural::{self, SceneKind};
use gridrt_scene::rays::{camera_rays, random_rays};
use gridrt_scene::{Camera, Hit, Mesh, Ray};

use super::common::{gpu, hostile_scenes};

/// Rays per scene in the full matrix (`GRIDRT_FULL_MATRICES=1`); a tenth by default.
const RAYS: usize = 100_000;

fn rays_for(mesh: &Mesh, n: usize) -> Vec<Ray> {
    let b = mesh.bounds();
    let mut r = random_rays(&b, n / 2, 7);
    r.extend(camera_rays(&Camera::fit(&b, 4.0 / 3.0), n - n / 2));
    r
}

/// Condition number of a hit: the sum of the magnitudes of the edge functions' products over
/// |det|. Rounding errors in the products (ε relative) reach t magnified by this; it is ~1 for
/// a well-shaped triangle seen head-on and large for slivers at grazing angles.
fn condition(r: &Ray, tri: &[Vec3; 3]) -> f64 {
    let p = PreparedRay::new(r).unwrap();
    let sh = |v: Vec3| {
        let a = v - p.org;
        ((a[p.kx] - p.sx * a[p.kz]) as f64, (a[p.ky] - p.sy * a[p.kz]) as f64)
    };
    let ((ax, ay), (bx, by), (cx, cy)) = (sh(tri[0]), sh(tri[1]), sh(tri[2]));
    let mags =
        (cx * by).abs() + (cy * bx).abs() + (ax * cy).abs() + (ay * cx).abs() + (bx * ay).abs() + (by * ax).abs();
    let det = (cx * by - cy * bx) + (ax * cy - ay * cx) + (bx * ay - by * ax);
    mags / det.abs().max(1e-300)
}

/// Ties are verified one by one above; in total they must stay rare, or something systematic is
/// wrong. Near-ties are a property of the scene (coincident or duplicated faces: Sponza has
/// ~0.16% of rays on such pairs), so they get a looser bound than the two rounding cases.
fn check_totals(total: &Tally) {
    assert!(total.near_ties <= total.rays / 100, "too many near-ties: {total:?}");
    assert!(
        total.boundary_ties + total.ill_conditioned <= total.rays / 10_000,
        "too many rounding differences: {total:?}"
    );
}

#[derive(Default, Debug)]
struct Tally {
    rays: usize,
    near_ties: usize,
    boundary_ties: usize,
    ill_conditioned: usize,
}

impl Tally {
    fn add(&mut self, o: &Tally) {
        self.rays += o.rays;
        self.near_ties += o.near_ties;
        self.boundary_ties += o.boundary_ties;
        self.ill_conditioned += o.ill_conditioned;
    }
}

fn compare_with(
    name: &str,
    tris: &[[Vec3; 3]],
    rays: &[Ray],
    kinds: &[GridKind],
    mailboxes: &[bool],
    base: &GridConfig,
) -> Tally {
    let ctx = gpu().expect("checked by caller");
    let exact = HitFloat::for_features(ctx.device.features()) == HitFloat::F64;
    let scene = GpuScene::new(ctx, tris).unwrap();
    let tracer = Tracer::new();
    let b = gridrt_scene::Aabb::from_points(tris.iter().flatten());
    let scale = b.min.abs().max(b.max.abs()).max_element().max(b.diagonal());
    let mut tally = Tally::default();
    for &kind in kinds {
        // The GPU kernels do not read the CPU's cell slabs (which skip cells, so tests, and
        // change no hit): the CPU grid is built without them so that its counts are the GPU's.
        let cfg = GridConfig { kind, cell_planes: CellPlanes::Off, ..*base };
        let (grid, _) = structure::build(tris, &cfg).unwrap();
        let gs = GpuStructure::new(ctx, &grid).unwrap();
        for traversal in Traversal::EXACT {
            for &mailbox in mailboxes {
                let opts = TraceOptions { traversal, mailbox, ..Default::default() };
                let (cpu_hits, _) = grid.trace_batch(tris, rays, opts, true);
                let cpu_stats: Vec<_> = rays.iter().map(|r| grid.trace(tris, r, opts).1).collect();
                let (gpu_hits, gpu_stats) = tracer.trace(ctx, &scene, &gs, rays, opts).unwrap();
                if exact {
                    // f64 hits (shaders/shared/hit_f64.wgsl): the CPU's operations, so every hit
                    // and every count is the CPU's, bit for bit.
                    let bits = |h: Hit| (h.t.to_bits(), h.triangle, h.u.to_bits(), h.v.to_bits());
                    let differ: Vec<usize> = (0..rays.len())
                        .filter(|&i| bits(cpu_hits[i]) != bits(gpu_hits[i]) || cpu_stats[i] != gpu_stats[i])
                        .collect();
                    assert!(
                        differ.is_empty(),
                        "{name} {kind} {traversal} mailbox={mailbox}: f64 GPU hits differ from the CPU's on {} rays, e.g. ray {}: cpu {:?} {:?}, gpu {:?} {:?}",
                        differ.len(),
                        differ[0],
                        cpu_hits[differ[0]],
                        cpu_stats[differ[0]],
                        gpu_hits[differ[0]],
                        gpu_stats[differ[0]]
                    );
                }
                let mut bad = Vec::new();
                let mut ties = 0;
                let mut cell_diff = Vec::new();
                let mut boundary_ties = 0;
                let mut ill_conditioned = 0;
                for i in 0..rays.len() {
                    let (c, g) = (cpu_hits[i], gpu_hits[i]);
                    // t is relative to the ray's length scale: both sides round coordinates of
                    // magnitude ~ `scale`, so a hit at tiny t has an error ~ ulp(scale) / |d|.
                    let tol = 1e-5 * c.t.abs().max(scale / rays[i].d().length());
                    if cpu_stats[i].cells != gpu_stats[i].cells {
                        // Explained only by a hit whose t differs in the last bits (the GPU's
                        // FMA edge functions vs the CPU's f64) lying on a cell boundary: the
                        // stop test `t < t_exit` then goes the other way. Anything else fails.
                        if c.is_hit() && g.is_hit() && c.t.to_bits() != g.t.to_bits() {
                            boundary_ties += 1;
                        } else {
                            cell_diff.push(i);
                        }
                    }
                    if c.triangle == g.triangle {
                        if c.is_hit() && (c.t - g.t).abs() > tol {
                            // Allowed only as far as the hit's conditioning explains it.
                            let cond = condition(&rays[i], &tris[c.triangle as usize]);
                            let bound = 16.0 * f32::EPSILON as f64 * cond * (tol / 1e-5) as f64;
                            if ((c.t - g.t).abs() as f64) <= bound {
                                ill_conditioned += 1;
                            } else {
                                bad.push(format!("ray {i}: t {} vs {} (condition {cond:.1})", c.t, g.t));
                            }
                        }
                        continue;
                    }
                    // Different triangles: a near-tie if the GPU's triangle is hit (by the CPU
                    // test) within 1e-5 relative of the CPU's t.
                    let pr = PreparedRay::new(&rays[i]).unwrap();
                    let alt = (g.is_hit()).then(|| intersect(&pr, &tris[g.triangle as usize])).flatten();
                    let tie = c.is_hit() && g.is_hit() && alt.is_some_and(|a| (a.t - c.t).abs() <= tol);
                    if tie {
                        ties += 1;
                    } else {
                        bad.push(format!("ray {i} {:?}: cpu {c:?} gpu {g:?}", rays[i]));
                    }
                }
                println!(
                    "{name} {kind} {traversal} mailbox={mailbox}: {} rays, {ties} near-ties, {boundary_ties} hits on a cell boundary (cells differ by rounding of t), {ill_conditioned} ill-conditioned hits (t differs > 1e-5 within the condition bound)",
                    rays.len(),
                );
                assert!(
                    bad.is_empty(),
                    "{name} {kind} {traversal}: {} rays differ:\n{}",
                    bad.len(),
                    bad[..bad.len().min(5)].join("\n")
                );
                assert!(
                    cell_diff.is_empty(),
                    "{name} {kind} {traversal}: cells visited differ on {} rays, e.g. ray {} cpu {:?} gpu {:?}",
                    cell_diff.len(),
                    cell_diff[0],
                    cpu_stats[cell_diff[0]],
                    gpu_stats[cell_diff[0]]
                );
                tally.rays += rays.len();
                tally.near_ties += ties;
                tally.boundary_ties += boundary_ties;
                tally.ill_conditioned += ill_conditioned;
            }
        }
    }
    tally
}

#[test]
fn gpu_matches_cpu_on_procedural_scenes() {
    if gpu().is_none() {
        return;
    }
    let scenes = [
        ("mountain", procedural::generate(SceneKind::Mountain, 6, 1).mesh),
        ("sphereflake", procedural::sphereflake(1, 2).mesh),
        ("particles", procedural::generate(SceneKind::Particles, 20_000, 2).mesh),
        ("slivers", procedural::generate(SceneKind::Slivers, 3000, 3).mesh),
        ("teapot-in-stadium", procedural::generate(SceneKind::TeapotInStadium, 1, 4).mesh),
    ];
    compare_scenes(scenes.into_iter().map(|(name, mesh)| (name.to_string(), mesh)), &[false, true]);
}

/// Every kind on each scene (builds: which to trace through, serial and/or parallel), then the
/// totals: ties and ill-conditioned hits are rounding coincidences, rare, or something is wrong.
fn compare_scenes(scenes: impl Iterator<Item = (String, Mesh)>, builds: &[bool]) {
    let mut total = Tally::default();
    for (name, mesh) in scenes {
        let rays = rays_for(&mesh, gridrt_testkit::matrix_rays(RAYS));
        total.add(&compare_with(&name, &mesh.triangles(), &rays, &GridKind::ALL, builds, &GridConfig::default()));
    }
    println!("total: {total:?}");
    check_totals(&total);
}

#[test]
fn gpu_matches_cpu_on_shared_scenes() {
    if gpu().is_none() {
        return;
    }
    let scenes = gridrt_testkit::shared_scenes().into_iter().map(|p| {
        let (mesh, _) = gridrt_scene::gltf_load::load_path(&p).unwrap();
        (p.file_name().unwrap().to_string_lossy().to_string(), mesh)
    });
    compare_scenes(scenes, &[true]);
}

/// The hierarchy kernel keeps its saved parent levels in named variables (one per depth, a
/// switch picks one): a multi-resolution grid as deep as the builders allow must use them all.
#[test]
fn gpu_matches_cpu_through_the_deepest_hierarchy() {
    if gpu().is_none() {
        return;
    }
    let mesh = procedural::generate(SceneKind::Particles, 3000, 5).mesh;
    let tris = mesh.triangles();
    let cfg = GridConfig {
        resolution: Some(Resolution::Explicit([2, 2, 2])),
        multires: MultiresOptions {
            policy: Policy::Octree,
            max_depth: hierarchy::MAX_DEPTH as u32 - 1,
            always_subdivide: true,
            ..MultiresOptions::default()
        },
        ..GridConfig::default()
    };
    let (grid, _) = structure::build(&tris, &GridConfig { kind: GridKind::Multires, ..cfg }).unwrap();
    let levels = match &grid {
        AnyGrid::Multires(h) => h.stats(0).levels,
        _ => unreachable!("built a multires grid"),
    };
    assert_eq!(levels, hierarchy::MAX_DEPTH as u32, "the test hierarchy must reach the deepest level");
    let t =
        compare_with("deep particles", &tris, &rays_for(&mesh, 20_000), &[GridKind::Multires], &[false, true], &cfg);
    check_totals(&t);
}

/// Hostile geometry (CPU: crates/grid/tests/suite/hostile.rs): far from the origin, triangles on
/// a lattice's planes (cell walls), coincident copies and degenerate triangles.
#[test]
fn gpu_matches_cpu_on_hostile_scenes() {
    if gpu().is_none() {
        return;
    }
    let base = procedural::generate(SceneKind::Particles, 3000, 9).mesh;
    let mut far = base.clone();
    far.positions.iter_mut().for_each(|p| *p = *p * 1e3 + Vec3::new(3.0e6, -2.5e6, 1.0e6));
    let mut copies = base.clone();
    let n = copies.indices.len();
    for i in 0..n / 2 {
        let t = copies.indices[i];
        copies.indices.push(t);
        copies.indices.push([t[0], t[1], t[1]]);
    }
    let mesh_of = |tris: Vec<[Vec3; 3]>| Mesh {
        positions: tris.iter().flatten().copied().collect(),
        indices: (0..tris.len() as u32).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect(),
    };
    let hostile = |name: &str| hostile_scenes().into_iter().find(|(n, _)| *n == name).expect("a hostile scene").1;
    let mut scenes = vec![
        ("far from the origin", far),
        ("on cell walls", mesh_of(hostile("on cell walls"))),
        ("coincident and degenerate", copies),
    ];
    // Coordinates of 1e29 overflow the f32 edge functions' products, which only the f64 hit test
    // decides (shaders/shared/hit_f64.wgsl): with f32 hits such triangles are never hit.
    if HitFloat::for_features(gpu().unwrap().device.features()) == HitFloat::F64 {
        scenes.push(("huge (1e29)", mesh_of(hostile("huge (1e29)"))));
    }
    compare_scenes(scenes.into_iter().map(|(name, mesh)| (name.to_string(), mesh)), &[true]);
}

/// A dispatch the device refuses (here a macrocell structure without its occupancy bits, so its
/// bind group does not match the kernel) is an error, not a buffer of zeroed hits.
#[test]
fn refused_trace_is_an_error() {
    if gpu().is_none() {
        return;
    }
    // A device of its own: device errors are per device, and the shared one serves other tests.
    let ctx = gridrt_gpu::GpuContext::new_headless_blocking().unwrap();
    let mesh = procedural::generate(SceneKind::Particles, 500, 3).mesh;
    let tris = mesh.triangles();
    let (grid, _) = structure::build(&tris, &GridConfig { kind: GridKind::Macrocell, ..Default::default() }).unwrap();
    let scene = GpuScene::new(&ctx, &tris).unwrap();
    let mut gs = GpuStructure::new(&ctx, &grid).unwrap();
    gs.extra = None;
    let rays = rays_for(&mesh, 256);
    let err = Tracer::new().trace(&ctx, &scene, &gs, &rays, TraceOptions::default()).unwrap_err();
    assert!(err.to_string().contains("bind group") || err.to_string().contains("Bind"), "{err}");
}
