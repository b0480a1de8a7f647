//! The GPU grid build against the CPU's: the same bounds, and flat grids equal cell for cell and
//! reference for reference, on generated scenes (huge, tiny, degenerate, far from the origin,
//! at scales 1e-18 and 1e29, on cell walls),
//! at several resolutions (scan levels 1 to 3), and on the shared scenes; a GPU-built grid
//! traces like the CPU-built one.

use glam::Vec3;
use gridrt_gpu::build::GridBuilder;
use gridrt_gpu::upload::{GpuScene, GpuStructure};
use gridrt_grid::build::{BuildOptions, PhaseTimes};
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
