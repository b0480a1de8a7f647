//! Hostile geometry and rays, generated from seeds: scenes far from the origin or at extreme
//! scales, coincident and degenerate triangles, triangles lying on cell walls, a huge triangle
//! among tiny ones; rays starting on triangles and walls, running along walls, with subnormal
//! or huge direction components and segments ending exactly at a hit. Every kind, insertion and
//! exact traversal, single rays, interleaved walks and packets, must equal brute force bit for
//! bit (occlusion queries: whether each ray is occluded).
//! `GRIDRT_HOSTILE_SEEDS=N` runs N seeds (default 12).

use glam::Vec3;
use gridrt_grid::trace::interleaved::trace_grid_interleaved;
use gridrt_grid::trace::{Query, TraceOptions};
use gridrt_grid::{AnyGrid, BuildOptions, GridConfig, GridKind, InsertMode, PacketOptions, Traversal, structure};
use gridrt_scene::rng::Rng;
use gridrt_scene::{Aabb, Camera, Hit, Ray};

use super::coherent::shadow_rays;
use super::common::{assert_same_hits, assert_same_occlusion, reference};

/// A hostile scene of `seed`'s kind, and its name.
fn scene(seed: u64) -> (String, Vec<[Vec3; 3]>) {
    let mut rng = Rng::new(seed);
    let mut tri = |c: Vec3, s: f32| [0, 1, 2].map(|_| c + (rng.unit_vector() * s));
    let mut tris: Vec<[Vec3; 3]> = Vec::new();
    let kind = seed % 6;
    // A base cloud of small triangles in the unit cube.
    let mut base = Rng::new(seed ^ 0x5eed);
    for _ in 0..600 {
        let c = Vec3::new(base.f32(), base.f32(), base.f32());
        tris.push(tri(c, 0.03));
    }
    let name = match kind {
        0 => {
            // Far from the origin: f32 keeps ~7 digits, the cells are a few ulps wide.
            for t in &mut tris {
                *t = t.map(|p| p * 1e3 + Vec3::new(3.0e6, -2.5e6, 1.0e6));
            }
            "far from the origin"
        }
        1 => {
            // Extreme scales, tiny and huge.
            let s = [1e-18, 1e18, 1e-30, 1e30][(seed / 6 % 4) as usize];
            for t in &mut tris {
                *t = t.map(|p| p * s);
            }
            "extreme scale"
        }
        2 => {
            // Coincident copies (ties in t, broken by the triangle index) and degenerate
            // triangles (a repeated corner, collinear corners).
            let n = tris.len();
            for i in 0..n / 3 {
                tris.push(tris[i * 3]);
                let [a, b, _] = tris[i * 3 + 1];
                tris.push([a, b, b]);
                tris.push([a, (a + b) * 0.5, b]);
            }
            "coincident and degenerate"
        }
        3 => {
            // Axis-aligned triangles on the planes of a lattice (cell walls at many
            // resolutions: multiples of 1/64 of the unit cube).
            for k in 0..400 {
                let q = |v: f32| (v * 64.0).round() / 64.0;
                let (a, u, v) = (k % 3, (k + 1) % 3, (k + 2) % 3);
                let mut p = [Vec3::ZERO; 3];
                let w = q(base.f32());
                let (u0, v0) = (q(base.f32()), q(base.f32()));
                for (j, c) in p.iter_mut().enumerate() {
                    c[a] = w;
                    c[u] = u0 + if j == 1 { 0.125 } else { 0.0 };
                    c[v] = v0 + if j == 2 { 0.125 } else { 0.0 };
                }
                tris.push(p);
            }
            "on cell walls"
        }
        4 => {
            // One huge triangle around tiny ones (the teapot in the stadium, far worse).
            tris.push([Vec3::new(-1e5, -1e5, 0.5), Vec3::new(1e5, -1e5, 0.5), Vec3::new(0.0, 1e5, 0.5)]);
            for t in &mut tris[..300] {
                *t = t.map(|p| p * 1e-4 + Vec3::splat(0.5));
            }
            "huge among tiny"
        }
        _ => {
            // Long slivers across the scene, nearly parallel to the axes.
            for _ in 0..200 {
                let a = Vec3::new(base.f32(), base.f32(), base.f32());
                let axis = (base.below(3)) as usize;
                let mut b = a;
                b[axis] += 1.0;
                let mut c = a;
                c[(axis + 1) % 3] += 1e-6;
                tris.push([a, b, c]);
            }
            "slivers"
        }
    };
    (format!("seed {seed}: {name}"), tris)
}

/// Rays that probe the scene's edge cases: from its triangles' corners, centroids and edges,
/// along lattice walls, with odd directions and segments ending at a hit.
fn rays(tris: &[[Vec3; 3]], seed: u64, count: usize) -> Vec<Ray> {
    let b = Aabb::from_points(tris.iter().flatten());
    let mut rng = Rng::new(seed ^ 0xbad);
    let ext = b.extent().max_element().max(f32::MIN_POSITIVE);
    let odd_dir = |rng: &mut Rng| -> Vec3 {
        let mut d = rng.unit_vector();
        match rng.below(5) {
            0 => d[rng.below(3) as usize] = 0.0,
            1 => d[rng.below(3) as usize] = 1e-40, // subnormal
            2 => d = Vec3::ZERO.with_x(1.0) * if rng.below(2) == 0 { 1.0 } else { -1.0 },
            3 => d *= [1e30, 1e37, 3e38, 1e-30][rng.below(4) as usize],
            _ => {}
        }
        d
    };
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        let t = tris[rng.below(tris.len() as u64) as usize];
        let o = match rng.below(5) {
            0 => t[rng.below(3) as usize],
            1 => (t[0] + t[1] + t[2]) / 3.0,
            2 => t[0] + (t[1] - t[0]) * rng.f32(),
            // On a lattice wall of the box (cells of most resolutions).
            3 => {
                let mut p = b.min + b.extent() * Vec3::new(rng.f32(), rng.f32(), rng.f32());
                let a = rng.below(3) as usize;
                p[a] = b.min[a] + b.extent()[a] * (rng.below(9) as f32 / 8.0);
                p
            }
            _ => b.min - Vec3::splat(0.1 * ext) + (b.extent() + Vec3::splat(0.2 * ext)) * rng.f32(),
        };
        let d = odd_dir(&mut rng);
        let (tmin, tmax) = match rng.below(4) {
            0 => (0.0, f32::INFINITY),
            1 => (-f32::INFINITY, f32::INFINITY),
            2 => (0.0, ext / d.length().max(f32::MIN_POSITIVE) * rng.f32()),
            _ => (1e-3 * ext / d.length().max(f32::MIN_POSITIVE), f32::INFINITY),
        };
        out.push(Ray::new(o, d, tmin, tmax));
    }
    // Segments that end exactly at their closest hit, and rays aimed at corners from outside.
    let (hits, _) = reference(tris, &out);
    let ends: Vec<Ray> = out.iter().zip(&hits).filter(|(_, h)| h.is_hit()).map(|(r, h)| r.ending_at(h.t)).collect();
    out.extend(ends.into_iter().take(count / 4));
    for _ in 0..count / 4 {
        let t = tris[rng.below(tris.len() as u64) as usize];
        let target = t[rng.below(3) as usize];
        let o = target + rng.unit_vector() * ext;
        out.push(Ray::new(o, target - o, 0.0, f32::INFINITY));
    }
    out
}

fn seeds() -> u64 {
    std::env::var("GRIDRT_HOSTILE_SEEDS").ok().and_then(|s| s.parse().ok()).unwrap_or(12)
}

/// `check(name, triangles, rays, brute force's hits)` for each seed's scene and `count` of its
/// rays (and the extra segments and corner rays [`rays`] adds).
fn each_case(count: usize, mut check: impl FnMut(&str, &[[Vec3; 3]], &[Ray], &[Hit])) {
    for seed in 0..seeds() {
        let (name, tris) = scene(seed);
        let rays = rays(&tris, seed, count);
        let (expected, _) = reference(&tris, &rays);
        check(&name, &tris, &rays, &expected);
    }
}

#[test]
fn hostile_scenes_and_rays_equal_brute_force() {
    each_case(3000, |name, tris, rays, expected| {
        let hits = expected.iter().filter(|h| h.is_hit()).count();
        println!("{name}: {} triangles, {} rays, {hits} hits", tris.len(), rays.len());
        for kind in GridKind::ALL {
            for insert in InsertMode::ALL {
                let cfg = GridConfig { kind, build: BuildOptions { insert, parallel: true }, ..GridConfig::default() };
                let (grid, _) = structure::build(tris, &cfg).unwrap_or_else(|e| panic!("{name} {kind}: {e}"));
                for traversal in Traversal::EXACT {
                    let opts = TraceOptions { traversal, mailbox: true, ..Default::default() };
                    let (hits, _) = grid.trace_batch(tris, rays, opts, true);
                    assert_same_hits(&format!("{name} {kind} {insert:?} {traversal}"), rays, expected, &hits);
                    let any = TraceOptions { query: Query::Any, ..opts };
                    let (hits, _) = grid.trace_batch(tris, rays, any, true);
                    assert_same_occlusion(
                        &format!("{name} {kind} {insert:?} {traversal} any"),
                        tris,
                        rays,
                        expected,
                        &hits,
                    );
                }
                // The interleaved walks (which large grids and incoherent rays take), by themselves.
                let mut hits = vec![Hit::MISS; rays.len()];
                let opts = TraceOptions::MAILBOX;
                match &grid {
                    AnyGrid::Flat(f) => trace_grid_interleaved(f, tris, rays, &mut hits, opts),
                    AnyGrid::Macrocell(m) => trace_grid_interleaved(m, tris, rays, &mut hits, opts),
                    AnyGrid::Proximity(p) => trace_grid_interleaved(p, tris, rays, &mut hits, opts),
                    _ => continue,
                };
                assert_same_hits(&format!("{name} {kind} {insert:?} interleaved"), rays, expected, &hits);
            }
        }
    });
}

#[test]
fn hostile_scenes_in_packets_equal_brute_force() {
    for seed in 0..seeds() {
        let (name, tris) = scene(seed);
        let b = Aabb::from_points(tris.iter().flatten());
        let (w, h) = (48, 40);
        // The camera framing the scene, and one inside it looking along an axis (its rays run
        // along the lattice's walls for some pixels).
        let cams = [
            Camera::fit(&b, w as f32 / h as f32),
            Camera { eye: b.center(), target: b.center() + Vec3::X, up: Vec3::Y, vfov_deg: 60.0 },
        ];
        for cam in cams {
            let rays = gridrt_scene::rays::image_rays(&cam, w, h);
            let (expected, _) = reference(&tris, &rays);
            for kind in GridKind::ALL {
                let (grid, _) = structure::build(&tris, &GridConfig { kind, ..GridConfig::default() }).unwrap();
                for tile in [4, 8] {
                    let packets = PacketOptions { tile, mailbox: true };
                    let (hits, _, _) =
                        grid.trace_packets(&tris, &rays, w as usize, TraceOptions::MAILBOX, packets, true);
                    assert_same_hits(&format!("{name} {kind} packets {tile}"), &rays, &expected, &hits);
                    let any = TraceOptions { query: Query::Any, ..TraceOptions::MAILBOX };
                    let (hits, _, _) = grid.trace_packets(&tris, &rays, w as usize, any, packets, true);
                    assert_same_occlusion(&format!("{name} {kind} packets {tile} any"), &tris, &rays, &expected, &hits);
                    // Shadow packets: from the hits towards a light outside the box.
                    let light = b.max + b.extent() * 0.7;
                    let shadows = shadow_rays(&rays, &expected, light, b.diagonal(), false);
                    let (want, _) = reference(&tris, &shadows);
                    let (hits, _, _) = grid.trace_packets(&tris, &shadows, w as usize, any, packets, true);
                    assert_same_occlusion(
                        &format!("{name} {kind} shadow packets {tile}"),
                        &tris,
                        &shadows,
                        &want,
                        &hits,
                    );
                }
            }
        }
    }
}

/// The hostile scenes and rays through grids the auto resolution would not choose: one cell,
/// 1024 cells along one axis, flat slabs, macrocell edges 2 and 16, a multires octree as deep as
/// allowed (every cell subdivided), closest hits with every exact walker.
#[test]
fn hostile_scenes_in_odd_grids_equal_brute_force() {
    use gridrt_grid::Resolution;
    use gridrt_grid::multires::{MultiresOptions, Policy};
    each_case(1500, |name, tris, rays, expected| {
        let explicit = |r: [u32; 3]| Some(Resolution::Explicit(r));
        let mut configs = Vec::new();
        for res in [[1, 1, 1], [1024, 1, 1], [3, 300, 2], [64, 64, 1]] {
            configs.push(GridConfig { kind: GridKind::Flat, resolution: explicit(res), ..GridConfig::default() });
            configs.push(GridConfig { kind: GridKind::Proximity, resolution: explicit(res), ..GridConfig::default() });
        }
        for a in [2, 16] {
            configs.push(GridConfig { kind: GridKind::Macrocell, macro_size: Some(a), ..GridConfig::default() });
        }
        configs.push(GridConfig {
            kind: GridKind::Macrocell,
            macro_size: Some(8),
            resolution: explicit([37, 5, 130]),
            ..GridConfig::default()
        });
        configs.push(GridConfig {
            kind: GridKind::Multires,
            resolution: explicit([2, 2, 2]),
            multires: MultiresOptions {
                policy: Policy::Octree,
                max_depth: gridrt_grid::hierarchy::MAX_DEPTH as u32 - 1,
                always_subdivide: true,
                ..MultiresOptions::default()
            },
            ..GridConfig::default()
        });
        for cfg in configs {
            let (grid, _) = structure::build(tris, &cfg).unwrap_or_else(|e| panic!("{name} {cfg:?}: {e}"));
            for traversal in Traversal::EXACT {
                let opts = TraceOptions { traversal, mailbox: true, ..Default::default() };
                let (hits, _) = grid.trace_batch(tris, rays, opts, true);
                let what = format!("{name} {} {:?} A={:?} {traversal}", cfg.kind, cfg.resolution, cfg.macro_size);
                assert_same_hits(&what, rays, expected, &hits);
            }
        }
    });
}

/// The experimental irregular grid (merged and expanded cells) on the hostile scenes and rays.
#[test]
fn hostile_scenes_in_the_irregular_grid_equal_brute_force() {
    use gridrt_grid::irregular::{IrregularGrid, IrregularOptions};
    use gridrt_grid::{CostModel, Resolution, build_flat};
    each_case(1500, |name, tris, rays, expected| {
        let opts = BuildOptions { insert: InsertMode::BoundingBox, parallel: true };
        let (flat, _, _) = build_flat(tris, Resolution::Auto, &CostModel::memory_aware(), opts).unwrap();
        for expand in [false, true] {
            let irr = IrregularGrid::from_flat(&flat, IrregularOptions { expand, ..Default::default() });
            let got: Vec<Hit> = rays.iter().map(|r| irr.trace(tris, r, TraceOptions::MAILBOX).0).collect();
            assert_same_hits(&format!("{name} irregular expand={expand}"), rays, expected, &got);
        }
    });
}

/// The hostile rays (no image, no coherence: odd directions, segments, origins on triangles)
/// traced as packets of a 30-ray-wide "image": every packet, coherent or not, equals brute force.
#[test]
fn hostile_rays_as_packets_equal_brute_force() {
    for seed in 0..seeds() {
        let (name, tris) = scene(seed);
        let mut rays = rays(&tris, seed, 1500);
        rays.truncate(rays.len() / 30 * 30);
        let (expected, _) = reference(&tris, &rays);
        for kind in [GridKind::Flat, GridKind::Macrocell, GridKind::Proximity] {
            let (grid, _) = structure::build(&tris, &GridConfig { kind, ..GridConfig::default() }).unwrap();
            for tile in [2, 5, 8] {
                let packets = PacketOptions { tile, mailbox: true };
                let (hits, _, _) = grid.trace_packets(&tris, &rays, 30, TraceOptions::MAILBOX, packets, true);
                assert_same_hits(&format!("{name} {kind} packets {tile} of hostile rays"), &rays, &expected, &hits);
            }
        }
    }
}

/// A scene scaled by a power of two (exact in f32) gets the same grid at every scale from 2^-90
/// to 2^90: the same resolution and the same cells and references (a grid box with an absolute
/// floor once put a scene nanometres across into one cell), and its rays, scaled alike, the same
/// hits. Every kind and insertion.
#[test]
fn grids_are_the_same_at_every_scale() {
    let (_, tris) = scene(6);
    // Rays whose direction components stay normal f32 at every scale (the hostile subnormal
    // and huge ones would underflow or overflow there, and are other rays then).
    let ordinary = |r: &Ray| r.d().to_array().iter().all(|c| *c == 0.0 || (1e-6..1e6).contains(&c.abs()));
    let rays: Vec<Ray> = rays(&tris, 6, 1500).into_iter().filter(ordinary).collect();
    for kind in GridKind::ALL {
        for insert in InsertMode::ALL {
            let cfg = GridConfig { kind, build: BuildOptions { insert, parallel: true }, ..GridConfig::default() };
            let (grid, _) = structure::build(&tris, &cfg).expect("unit scale");
            let (hits, _) = grid.trace_batch(&tris, &rays, TraceOptions::MAILBOX, true);
            for k in [-90, -60, -30, 30, 60, 90] {
                let s = 2f32.powi(k);
                let scaled: Vec<[Vec3; 3]> = tris.iter().map(|t| t.map(|p| p * s)).collect();
                let what = format!("{kind} {insert:?} at 2^{k}");
                let (g, _) = structure::build(&scaled, &cfg).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(g.cells_digest(), grid.cells_digest(), "{what}: another grid than at scale 1");
                // Origins scaled, directions as given: the same t for the same triangle.
                let moved: Vec<Ray> = rays.iter().map(|r| Ray::new(r.o() * s, r.d() * s, r.tmin, r.tmax)).collect();
                let (got, _) = g.trace_batch(&scaled, &moved, TraceOptions::MAILBOX, true);
                let same = |a: &Hit, b: &Hit| a.triangle == b.triangle && (!a.is_hit() || a.t == b.t);
                let bad = hits.iter().zip(&got).filter(|(a, b)| !same(a, b)).count();
                assert_eq!(bad, 0, "{what}: {bad} of {} rays hit otherwise than at scale 1", rays.len());
            }
        }
    }
}
