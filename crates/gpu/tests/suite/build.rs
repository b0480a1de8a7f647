//! The GPU grid build against the CPU's: the same bounds, and flat grids equal cell for cell and
//! reference for reference, on generated scenes (huge, tiny, degenerate, far from the origin,
//! at scales 1e-18 and 1e29, on cell walls),
//! at several resolutions (scan levels 1 to 3), and on the shared scenes; a GPU-built grid
//! traces like the CPU-built one.

use glam::Vec3;
use gridrt_gpu::build::GridBuilder;
use gridrt_gpu::upload::{GpuScene, GpuStructure};
use gridrt_grid::build::{BuildOptions, PhaseTimes};
use gridrt_grid::cell_plane::CellPlanes;
use gridrt_grid::geometry::GridGeometry;
use gridrt_grid::{
    AnyGrid, FlatGrid, GridConfig, GridKind, InsertMode, Resolution, TraceOptions, structure, triangle_bounds,
};
use gridrt_scene::procedural::{self, SceneKind};

use super::common::{gpu, hostile_scenes};

fn check(name: &str, tris: &[[Vec3; 3]], resolutions: &[[u32; 3]]) {
    let ctx = gpu().expect("checked by the caller");
    let builder = GridBuilder::new(ctx).unwrap();
    let scene = GpuScene::new(ctx, tris).unwrap();
    let bounds = builder.bounds(ctx, &scene).unwrap();
    let cpu_bounds = triangle_bounds(tris);
    assert_eq!(bounds, cpu_bounds, "{name}: bounds");
    for (&res, insert) in resolutions.iter().flat_map(|r| InsertMode::ALL.map(|i| (r, i))) {
        let geom = GridGeometry::new(&bounds, res);
        let opts = BuildOptions { insert, parallel: true };
        let cpu = FlatGrid::build(tris, geom, opts, &mut PhaseTimes::default()).unwrap();
        let g = builder.build_flat(ctx, &scene, geom, insert).unwrap();
        let AnyGrid::Flat(back) = builder.read_back(ctx, &g).unwrap() else { panic!("{name}: not a flat grid") };
        assert_eq!(back.occupied, cpu.occupied, "{name} {res:?} {insert:?}: occupancy words");
        assert_eq!(back.ref_start, cpu.ref_start, "{name} {res:?} {insert:?}: ref_start");
        assert_eq!(back.refs, cpu.refs, "{name} {res:?} {insert:?}: refs");
        assert_eq!(back, cpu, "{name} {res:?} {insert:?}");
        println!("{name} {res:?} {insert:?}: {} cells, {} refs, equal ({:?})", g.cells, g.refs, g.times);
    }
}

#[test]
fn gpu_build_equals_the_cpu_build() {
    if gpu().is_none() {
        return;
    }
    let far: Vec<[Vec3; 3]> = procedural::generate(SceneKind::Particles, 3000, 5)
        .mesh
        .triangles()
        .iter()
        .map(|t| t.map(|p| p * 10.0 + Vec3::new(1e5, -3e4, 7e3)))
        .collect();
    let mut degenerate = procedural::generate(SceneKind::Slivers, 2000, 6).mesh.triangles();
    degenerate.extend((0..200).map(|i| [Vec3::splat(i as f32 * 0.01); 3]));
    let scenes = [
        ("teapot-in-stadium", procedural::generate(SceneKind::TeapotInStadium, 1, 4).mesh.triangles()),
        ("particles", procedural::generate(SceneKind::Particles, 40_000, 2).mesh.triangles()),
        ("mountain", procedural::generate(SceneKind::Mountain, 6, 1).mesh.triangles()),
        ("far from the origin", far),
        ("slivers and points", degenerate),
        ("one triangle", vec![[Vec3::ZERO, Vec3::X, Vec3::Y]]),
    ];
    for (name, tris) in scenes.iter().chain(&hostile_scenes()) {
        // 1 cell; a scan of one block (4096 elements); two levels.
        check(name, tris, &[[1, 1, 1], [7, 5, 3], [64, 40, 50], [80, 70, 60]]);
    }
    // Three scan levels: more than 4096² cells + 1.
    check("one triangle, 17M cells", &scenes[5].1, &[[260, 256, 256]]);
    // Exact insertion where f32 cannot decide: planes touching cells' (enlarged) cubes exactly.
    check("touching planes", &touching_planes(), &[[256, 256, 256]]);
}

/// Triangles whose planes touch a cell's cube (half size 0.5 + the insertion margin) exactly or
/// miss or cut it by a unit in the last place of a coordinate, on a grid of unit cells from the
/// origin (256³ over [0, 256]³): f64 holds the normal (products of ~40 bits) and rounds little,
/// while f32 rounds it and the sums after it by far more than the offsets, so f32 alone would land
/// on either side. Exact insertion on the GPU must decide them in f64, as the CPU does.
fn touching_planes() -> Vec<[Vec3; 3]> {
    let h = 0.5 + gridrt_grid::geometry::INSERT_MARGIN_CELLS as f32;
    let mut tris = vec![[Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)]];
    tris.push([Vec3::splat(256.0), Vec3::new(255.0, 256.0, 256.0), Vec3::new(256.0, 255.0, 256.0)]);
    let mut seed = 0x9e37_79b9u32;
    let mut next = |n: u32| {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed % n
    };
    for _ in 0..400 {
        // The plane a·x + b·y + z = k through the corner of cube c nearest to it (or farthest
        // below, with the sign s): k = a·cx + b·cy + cz ± h (a + b + 1).
        let (a, b) = ((1 + next(4)) as f32, (1 + next(4)) as f32);
        let s = if next(2) == 0 { 1.0 } else { -1.0 };
        let c = Vec3::new(80.0 + next(40) as f32, 80.0 + next(40) as f32, 0.0) + Vec3::splat(0.5);
        let c = Vec3::new(c.x, c.y, 120.5);
        // Touching, or a few units of the last place of z (2^-16 at 128–256) off.
        let off = (next(5) as f32 - 2.0) / 65536.0;
        let k = a * c.x + b * c.y + c.z + s * h * (a + b + 1.0) + off;
        // Edges of 19 and 20 significant bits (multiples of 2^-16, as every coordinate), so the
        // normal's components need about 40 bits: f32 rounds them, f64 holds them.
        let p = (2 * next(1 << 19) + (1 << 19) + 1) as f32 / 65536.0;
        let q = (2 * next(1 << 18) + (1 << 18) + 1) as f32 / 65536.0;
        let v0 = Vec3::new(c.x - 2.0, c.y - 1.0, 0.0);
        let v0 = Vec3::new(v0.x, v0.y, k - a * v0.x - b * v0.y);
        let v1 = v0 + Vec3::new(p, 0.0, -a * p);
        let v2 = v0 + Vec3::new(0.0, q, -b * q);
        tris.push([v0, v1, v2]);
    }
    tris
}

#[test]
fn gpu_build_of_shared_scenes_at_auto_resolution() {
    let Some(ctx) = gpu() else { return };
    for path in gridrt_testkit::shared_scenes().into_iter().take(if gridrt_testkit::full_matrices() { 99 } else { 2 }) {
        let (mesh, _) = gridrt_scene::gltf_load::load_path(&path).unwrap();
        let tris = mesh.triangles();
        let cfg = GridConfig { kind: GridKind::Flat, resolution: Some(Resolution::Auto), ..GridConfig::default() };
        let (cpu, _) = structure::build(&tris, &cfg).unwrap();
        let res = cpu.geometry().res.to_array();
        check(&path.file_name().unwrap().to_string_lossy(), &tris, &[res]);
        // Traced through the GPU-built buffers: the same hits as through the uploaded CPU grid.
        let builder = GridBuilder::new(ctx).unwrap();
        let scene = GpuScene::new(ctx, &tris).unwrap();
        let g = builder.build_flat(ctx, &scene, *cpu.geometry(), InsertMode::BoundingBox).unwrap();
        let uploaded = GpuStructure::new(ctx, &cpu).unwrap();
        let rays = gridrt_scene::rays::random_rays(&mesh.bounds(), 2000, 9);
        let tracer = gridrt_gpu::Tracer::new();
        let a = tracer
            .trace(ctx, &scene, &g.structure, &rays, TraceOptions { mailbox: true, ..Default::default() })
            .unwrap();
        let b =
            tracer.trace(ctx, &scene, &uploaded, &rays, TraceOptions { mailbox: true, ..Default::default() }).unwrap();
        assert_eq!(a.0, b.0, "{}: hits", path.display());
    }
}

/// Through the whole pipeline (bounds, resolution choice, build): flat and macrocell grids
/// (A given, and A chosen by the cost model from the fine grid), with box and exact insertion,
/// equal the CPU's, digests included; other kinds are refused with a message.
#[test]
fn gpu_build_of_every_supported_configuration_equals_the_cpu() {
    let Some(ctx) = gpu() else { return };
    let builder = GridBuilder::new(ctx).unwrap();
    let scenes = [
        ("teapot-in-stadium", procedural::generate(SceneKind::TeapotInStadium, 1, 4).mesh.triangles()),
        ("particles", procedural::generate(SceneKind::Particles, 30_000, 8).mesh.triangles()),
    ];
    for (name, tris) in scenes.iter().chain(&hostile_scenes()) {
        let scene = GpuScene::new(ctx, tris).unwrap();
        let configs = [
            GridConfig { kind: GridKind::Flat, ..GridConfig::default() },
            GridConfig { kind: GridKind::Flat, resolution: Some(Resolution::Cubic(33)), ..GridConfig::default() },
            GridConfig { kind: GridKind::Macrocell, ..GridConfig::default() },
            GridConfig { kind: GridKind::Macrocell, macro_size: Some(4), ..GridConfig::default() },
            GridConfig {
                kind: GridKind::Macrocell,
                macro_size: Some(8),
                resolution: Some(Resolution::Cubic(50)),
                ..GridConfig::default()
            },
        ];
        let exact = |cfg: GridConfig| GridConfig {
            build: gridrt_grid::BuildOptions { insert: InsertMode::Exact, parallel: true },
            ..cfg
        };
        for cfg in configs.into_iter().flat_map(|c| [c, exact(c)]) {
            // The GPU build makes the cells and references; the CPU's cell slabs are an addition
            // of the CPU build (gridrt_grid::cell_plane), left out on both sides here.
            let cfg = GridConfig { cell_planes: CellPlanes::Off, ..cfg };
            let (cpu, report) = structure::build(tris, &cfg).unwrap();
            let g = builder.build(ctx, &scene, tris, &cfg).unwrap();
            let back = builder.read_back(ctx, &g).unwrap();
            assert_eq!(back, cpu, "{name} {cfg:?}");
            assert_eq!(back.cells_digest(), cpu.cells_digest());
            assert_eq!(g.macro_samples, report.macro_samples, "{name} {cfg:?}");
            println!("{name} {} A={:?}: equal, digest {:016x}", cfg.kind, g.macrocells, back.cells_digest());
        }
        for cfg in [
            GridConfig { kind: GridKind::Multires, ..GridConfig::default() },
            exact(GridConfig { kind: GridKind::TwoLevel, ..GridConfig::default() }),
        ] {
            let e = builder.build(ctx, &scene, tris, &cfg).unwrap_err().to_string();
            assert!(e.contains("use the CPU build"), "{e}");
        }
    }
}
