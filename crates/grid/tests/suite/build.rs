//! Build invariants: the compact layout, conservative insertion, determinism, resolution
//! policies and the cost model.

use glam::Vec3;
use gridrt_grid::insert::{InsertMode, tri_box_overlap};
use gridrt_grid::resolution::{self, CostModel, Resolution};
use gridrt_grid::{BuildOptions, FlatGrid, GridGeometry, PhaseTimes, build_flat, triangle_bounds};
use gridrt_scene::procedural::{self, SceneKind};

fn tris_of(kind: SceneKind, size: u32) -> Vec<[Vec3; 3]> {
    procedural::generate(kind, size, 5).mesh.triangles()
}

/// Below the interval: long slivers' bounding-box references grow with their boxes' volume, so
/// box insertion's T(m) keeps falling below one cell per triangle; its curve goes down until its
/// coarsest sample is no longer the one taken. Exact insertion keeps the interval, and a mesh's
/// curve has its least T(m) inside the interval, where nothing is added.
#[test]
fn auto_goes_below_the_interval_only_where_box_counts_keep_falling() {
    let aware = CostModel::memory_aware();
    let tris = tris_of(SceneKind::Slivers, 4000);
    let b = triangle_bounds(&tris);
    let lo = (tris.len() as f64).cbrt();
    let boxed = resolution::choose(&tris, &b, Resolution::Auto, &aware, InsertMode::BoundingBox, true);
    let exact = resolution::choose(&tris, &b, Resolution::Auto, &aware, InsertMode::Exact, true);
    assert!((exact.curve[0].m / lo - 1.0).abs() < 0.2, "{} vs {lo}", exact.curve[0].m);
    assert_eq!(aware.best_sample(&exact.curve).unwrap().cells, exact.curve[0].cells, "the interval's coarsest");
    assert!(boxed.curve.windows(2).all(|w| w[0].cells < w[1].cells), "{:?}", boxed.curve);
    let taken = aware.best_sample(&boxed.curve).unwrap();
    assert_eq!(taken.resolution, boxed.resolution);
    assert!(boxed.curve[0].m < taken.m && taken.m < 0.8 * lo, "{} taken, interval from {lo}", taken.m);
    // The interval's samples are the exact curve's resolutions, below them the added ones.
    let added = boxed.curve.len() - exact.curve.len();
    assert!(added > 0);
    let interval: Vec<_> = boxed.curve[added..].iter().map(|s| s.resolution).collect();
    assert_eq!(interval, exact.curve.iter().map(|s| s.resolution).collect::<Vec<_>>());
    for s in &boxed.curve[..added] {
        assert_eq!(s.n_m, resolution::count_refs(&tris, &b, s.resolution, InsertMode::BoundingBox, true), "{s:?}");
        assert!((s.cost - aware.cost(s.cells, s.n_m, tris.len())).abs() < 1e-9);
    }
    // A mesh: the interval alone.
    let mesh = tris_of(SceneKind::Mountain, 5);
    let mb = triangle_bounds(&mesh);
    let curve = resolution::choose(&mesh, &mb, Resolution::Auto, &aware, InsertMode::BoundingBox, true).curve;
    assert!((curve[0].m / (mesh.len() as f64).cbrt() - 1.0).abs() < 0.2, "{curve:?}");
}

#[test]
fn layout_is_consistent_and_sorted() {
    let tris = tris_of(SceneKind::Particles, 3000);
    for insert in InsertMode::ALL {
        let (g, _, _) =
            build_flat(&tris, Resolution::Cubic(17), &CostModel::default(), BuildOptions { insert, parallel: true })
                .unwrap();
        let table = g.cell_table();
        assert_eq!(table.len() as u64, g.geom.cell_count() + 1);
        assert_eq!(*table.last().unwrap() as usize, g.refs.len());
        assert!(table.windows(2).all(|w| w[0] <= w[1]));
        // The compact layout: an offset per occupied cell (each holds a reference), ranks that
        // count the occupied cells before each word, and the table rebuilding the same grid.
        assert!(g.ref_start.windows(2).all(|w| w[0] < w[1]), "an occupied cell without references");
        let mut rank = 0;
        for w in &g.occupied {
            assert_eq!(w.rank, rank);
            rank += w.bits.count_ones();
        }
        assert_eq!(rank as usize + 1, g.ref_start.len());
        assert_eq!(FlatGrid::new(g.geom, table.clone(), g.refs.clone()), g);
        for c in 0..g.geom.cell_count() as usize {
            let refs = g.cell(c);
            assert_eq!(refs, &g.refs[table[c] as usize..table[c + 1] as usize], "cell {c}");
            assert_eq!(g.is_occupied(c), !refs.is_empty());
            assert!(refs.windows(2).all(|w| w[0] < w[1]), "cell {c} not strictly increasing");
        }
        // Every triangle is referenced at least once.
        let mut seen = vec![false; tris.len()];
        for &r in &g.refs {
            seen[r as usize] = true;
        }
        assert!(seen.iter().all(|&s| s), "{insert:?}: a triangle is in no cell");
    }
}

#[test]
fn exact_insertion_is_a_subset_of_bbox_insertion_and_covers_the_triangle() {
    let tris = tris_of(SceneKind::Slivers, 2000);
    let opts = |insert| BuildOptions { insert, parallel: false };
    let (bb, _, _) =
        build_flat(&tris, Resolution::Cubic(24), &CostModel::default(), opts(InsertMode::BoundingBox)).unwrap();
    let (ex, _, _) = build_flat(&tris, Resolution::Cubic(24), &CostModel::default(), opts(InsertMode::Exact)).unwrap();
    assert!(ex.refs.len() < bb.refs.len() / 2, "slivers: exact {} vs bbox {}", ex.refs.len(), bb.refs.len());
    for c in 0..ex.geom.cell_count() as usize {
        let (e, b) = (ex.cell(c), bb.cell(c));
        assert!(e.iter().all(|t| b.contains(t)));
    }
    // Points sampled on each triangle lie in (or within the margin of) a cell holding it.
    let g = &ex.geom;
    for (i, t) in tris.iter().enumerate().step_by(7) {
        for (a, b) in [(0.2f32, 0.3f32), (0.9, 0.05), (0.0, 0.0), (0.5, 0.5)] {
            let p = t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b;
            let c = ((p - g.min) * g.inv_cell).floor().as_uvec3().min(g.res - 1);
            assert!(ex.cell(g.cell_index(c)).contains(&(i as u32)), "triangle {i} point {p} not in its cell {c}");
        }
    }
}

/// Exact insertion takes each row's cells between its first and last overlap untested (they
/// form a run): the cells equal those of the overlap test run cell by cell over the triangle's
/// whole range, on slivers, large triangles at every slant across many cells, and particles.
#[test]
fn exact_insertion_rows_equal_the_cell_by_cell_test() {
    use glam::{DVec3, UVec3};
    use gridrt_grid::geometry::INSERT_MARGIN_CELLS;
    use gridrt_grid::insert::{for_each_cell, prepare};
    let mut tris = tris_of(SceneKind::Slivers, 1500);
    tris.extend(tris_of(SceneKind::Particles, 1500));
    // Large triangles through the grid at many slants (a deterministic spread of corners).
    let mut h = 0x2545_f491u32;
    let mut next = || {
        h ^= h << 13;
        h ^= h >> 17;
        h ^= h << 5;
        (h % 10_000) as f32 / 10_000.0
    };
    for _ in 0..300 {
        tris.push(std::array::from_fn(|_| Vec3::new(next(), next(), next())));
    }
    let geom = GridGeometry::new(&triangle_bounds(&tris), [29, 31, 23]);
    let (mut cells, mut tested) = (0u64, 0u64);
    for t in &tris {
        let g = prepare(&geom, t, INSERT_MARGIN_CELLS);
        let mut rows = Vec::new();
        for_each_cell(&geom, &g, InsertMode::Exact, |c| rows.push(c));
        let mut each = Vec::new();
        for z in g.lo.z..=g.hi.z {
            for y in g.lo.y..=g.hi.y {
                for x in g.lo.x..=g.hi.x {
                    let c = UVec3::new(x, y, z);
                    let single = g.lo == g.hi;
                    if single || tri_box_overlap(&g.v, c.as_dvec3() + DVec3::splat(0.5), 0.5 + g.margin) {
                        each.push(geom.cell_index(c));
                    }
                }
            }
        }
        assert_eq!(rows, each, "{t:?}");
        cells += rows.len() as u64;
        tested += ((g.hi - g.lo + UVec3::ONE).as_u64vec3()).element_product();
    }
    // The large triangles make many rows of long runs.
    assert!(cells > 20_000 && cells * 4 < tested, "{cells} cells of {tested} candidates");
}

#[test]
fn tri_box_overlap_matches_known_cases() {
    use glam::DVec3;
    let t = [DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 1.0, 0.0)];
    assert!(tri_box_overlap(&t, DVec3::new(0.2, 0.2, 0.0), 0.1));
    assert!(!tri_box_overlap(&t, DVec3::new(0.9, 0.9, 0.0), 0.1)); // beyond the hypotenuse
    assert!(!tri_box_overlap(&t, DVec3::new(0.2, 0.2, 0.5), 0.1)); // above the plane
    assert!(tri_box_overlap(&t, DVec3::new(0.2, 0.2, 0.1), 0.1)); // touching counts
}

#[test]
fn parallel_build_is_bit_identical_to_serial() {
    for kind in [SceneKind::Particles, SceneKind::Slivers, SceneKind::Mountain] {
        let tris = tris_of(kind, if kind == SceneKind::Mountain { 6 } else { 40_000 });
        // A few slabs, and (1.9M cells) many slabs of at most 128k cells each, with the
        // triangles in several chunks; layers of 6 and 15 cells, so that one occupancy word
        // spans several slabs and slab edges fall inside words.
        for (insert, res) in [
            (InsertMode::BoundingBox, [37, 23, 41]),
            (InsertMode::Exact, [37, 23, 41]),
            (InsertMode::BoundingBox, [160, 120, 100]),
            (InsertMode::BoundingBox, [3, 2, 4]),
            (InsertMode::Exact, [3, 2, 4]),
            (InsertMode::BoundingBox, [5, 3, 700]),
        ] {
            // Exact insertion is slow: half the triangles (still two chunks).
            let tris = if insert == InsertMode::Exact { &tris[..tris.len() / 2] } else { &tris[..] };
            let geom = GridGeometry::new(&triangle_bounds(tris), res);
            let a = FlatGrid::build(tris, geom, BuildOptions { insert, parallel: false }, &mut PhaseTimes::default())
                .unwrap();
            let b = FlatGrid::build(tris, geom, BuildOptions { insert, parallel: true }, &mut PhaseTimes::default())
                .unwrap();
            assert!(a == b, "{kind:?} {insert:?} {res:?}");
        }
    }
}

/// A build into a previous build's arrays (a grid rebuilt every frame) is the same grid as a
/// build from nothing, whatever the arrays held: larger and smaller grids one after another
/// (arrays replaced when too small, cut, and lengthened within their capacity), both insertion
/// modes, the grid handed back each time.
#[test]
fn a_build_into_recycled_arrays_equals_a_fresh_build() {
    let mut scratch = gridrt_grid::BuildScratch::default();
    let mut previous = None;
    for (kind, size, insert, res) in [
        (SceneKind::Mountain, 5, InsertMode::BoundingBox, [17, 9, 23]),
        (SceneKind::Particles, 40_000, InsertMode::BoundingBox, [160, 120, 100]),
        (SceneKind::Mountain, 5, InsertMode::BoundingBox, [17, 9, 23]),
        (SceneKind::Slivers, 3_000, InsertMode::Exact, [37, 23, 41]),
        (SceneKind::Particles, 40_000, InsertMode::BoundingBox, [61, 64, 59]),
        (SceneKind::Mountain, 6, InsertMode::BoundingBox, [160, 120, 100]),
    ] {
        let tris = tris_of(kind, size);
        let geom = GridGeometry::new(&triangle_bounds(&tris), res);
        let opts = BuildOptions { insert, parallel: true };
        if let Some(g) = previous.take() {
            scratch.recycle(gridrt_grid::AnyGrid::Flat(g));
        }
        let fresh = FlatGrid::build(&tris, geom, opts, &mut PhaseTimes::default()).unwrap();
        let reused = FlatGrid::build_reusing(&tris, geom, opts, &mut PhaseTimes::default(), &mut scratch).unwrap();
        assert!(fresh == reused, "{kind:?} {insert:?} {res:?}");
        previous = Some(reused);
    }
}

#[test]
fn non_cubic_scenes_get_near_cubic_cells() {
    let b = gridrt_scene::Aabb { min: Vec3::ZERO, max: Vec3::new(100.0, 10.0, 1.0) };
    let r = resolution::cubic_cells(&b, 1000.0 * 100.0);
    let cell = Vec3::new(100.0 / r[0] as f32, 10.0 / r[1] as f32, 1.0 / r[2] as f32);
    assert!(cell.max_element() / cell.min_element() < 1.3, "{r:?} {cell}");
    // A flat scene (all z equal) still gets a valid grid, one cell thick.
    let flat = gridrt_scene::Aabb { min: Vec3::ZERO, max: Vec3::new(1.0, 1.0, 0.0) };
    let r = resolution::cubic_cells(&flat, 10_000.0);
    assert_eq!(r[2], 1);
    assert!(r[0] >= 50 && r[0] == r[1], "{r:?}");
}

#[test]
fn resolution_policies_follow_their_formulas() {
    let tris = tris_of(SceneKind::Particles, 8000);
    let b = triangle_bounds(&tris);
    let m = CostModel::default();
    let cells = |p| {
        let r = resolution::choose(&tris, &b, p, &m, InsertMode::BoundingBox, false).resolution;
        r.iter().map(|&x| x as f64).product::<f64>()
    };
    let n = tris.len() as f64;
    let near = |got: f64, want: f64| (got / want - 1.0).abs() < 0.25;
    assert!(near(cells(Resolution::Density(2.0)), 2.0 * n));
    assert!(near(cells(Resolution::Point), 2.0 * n * 5.0)); // eq. (1): 2N·Tinter/Tstep
    let line = (n * 5.0).powf(1.5).min(m.cell_cap(tris.len()) as f64);
    assert!(near(cells(Resolution::Line), line)); // eq. (2), capped by memory
    assert_eq!(
        resolution::choose(&tris, &b, Resolution::Explicit([3, 4, 5]), &m, InsertMode::BoundingBox, false).resolution,
        [3, 4, 5]
    );
    assert_eq!(
        resolution::choose(&tris, &b, Resolution::Cubic(40), &m, InsertMode::BoundingBox, false)
            .resolution
            .iter()
            .max(),
        Some(&40)
    );
    for s in ["auto", "point", "line", "density=3.5", "m=64", "10,20,30"] {
        assert!(s.parse::<Resolution>().is_ok(), "{s}");
    }
    for s in ["", "m=0", "density=-1", "1,2", "m=99999", "foo", "0,1,1"] {
        assert!(s.parse::<Resolution>().is_err(), "{s}");
    }
}

#[test]
fn guess_and_check_counts_exactly_and_picks_the_minimum() {
    let tris = tris_of(SceneKind::Mountain, 5);
    assert!(tris.len() <= resolution::EXACT_COUNT_LIMIT, "{} triangles are sampled", tris.len());
    let b = triangle_bounds(&tris);
    let model = CostModel::default();
    // The auto policy samples box insertion's N_m for either insertion mode.
    let choice = resolution::choose(&tris, &b, Resolution::Auto, &model, InsertMode::BoundingBox, true);
    let best = choice.curve.iter().min_by(|a, b| a.cost.total_cmp(&b.cost)).unwrap();
    assert_eq!(best.resolution, choice.resolution);
    assert_eq!(choice.curve, resolution::sample_curve(&tris, &b, &model, InsertMode::BoundingBox, true));
    for insert in InsertMode::ALL {
        let curve = resolution::sample_curve(&tris, &b, &model, insert, true);
        assert!(curve.len() >= 5, "{curve:?}");
        assert!(curve.windows(2).all(|w| w[0].m < w[1].m));
        // N_m from counting equals the reference count of the built grid, for some samples.
        for s in curve.iter().step_by(4) {
            let grid = FlatGrid::build(
                &tris,
                GridGeometry::new(&b, s.resolution),
                BuildOptions { insert, parallel: true },
                &mut PhaseTimes::default(),
            )
            .unwrap();
            assert_eq!(grid.refs.len() as u64, s.n_m);
            assert!((s.cost - model.cost(s.cells, s.n_m, tris.len())).abs() < 1e-9);
        }
        // The interval is the survey's: from (10N)^⅓ up.
        let lo = (10.0 * tris.len() as f64).cbrt();
        assert!((curve[0].m / lo - 1.0).abs() < 0.2, "{} vs {lo}", curve[0].m);
    }
    // Different constants move the optimum: expensive steps give coarser grids.
    let with_step = |t_step| {
        resolution::choose(&tris, &b, Resolution::Auto, &CostModel { t_step, ..model }, InsertMode::BoundingBox, true)
    };
    let (cheap, dear) = (with_step(0.02), with_step(1.0));
    let m = |c: &gridrt_grid::ResolutionChoice| c.resolution.iter().map(|&x| x as f64).product::<f64>();
    assert!(m(&cheap) > m(&dear), "{:?} vs {:?}", cheap.resolution, dear.resolution);
    // The memory term: sampled from one cell per triangle up, each sample's cost is T(m) plus
    // the grid's bytes per triangle weighted, and the choice is coarser than the survey's.
    let aware = CostModel::memory_aware();
    assert_eq!(aware.memory_weight, 2.0, "the weight calibrated on this machine (README)");
    // T(m) with the memory-aware model's cheaper triangle test.
    assert_eq!((aware.t_setup, aware.t_step, aware.t_inter), (1.0, 0.1, 0.35), "the README's values");
    let t_of = CostModel { t_inter: 0.35, ..model };
    let choice = resolution::choose(&tris, &b, Resolution::Auto, &aware, InsertMode::BoundingBox, true);
    let lo = (tris.len() as f64).cbrt();
    assert!((choice.curve[0].m / lo - 1.0).abs() < 0.2, "{} vs {lo}", choice.curve[0].m);
    for s in &choice.curve {
        // The term scaled by the share of the grid's bytes the cache does not hold.
        let bytes = 4.125 * s.cells as f64 + 4.0 * s.n_m as f64;
        let missed = bytes / (bytes + 1024.0 * 1024.0);
        let expected = t_of.cost(s.cells, s.n_m, tris.len()) + 0.1 * 2.0 * missed * bytes / tris.len() as f64;
        assert!((s.cost - expected).abs() < 1e-9, "{s:?}");
    }
    // Without the cache (the term as first calibrated) the weight applies whole.
    let uncached = CostModel { cache_bytes: 0.0, ..aware };
    let s = &choice.curve[0];
    let bytes = 4.125 * s.cells as f64 + 4.0 * s.n_m as f64;
    let whole = t_of.cost(s.cells, s.n_m, tris.len()) + 0.1 * 2.0 * bytes / tris.len() as f64;
    assert!((uncached.cost(s.cells, s.n_m, tris.len()) - whole).abs() < 1e-9);
    // The DRAM tier: the default's 16 MiB are far beyond this small grid (no term); with the
    // tier at a fraction of the grids' bytes, every byte beyond it weighs 8 cell steps more per
    // triangle, and the choice gets coarser.
    assert_eq!((aware.dram_bytes, aware.dram_weight), (16.0 * 1024.0 * 1024.0, 8.0), "the README's values");
    let dram = CostModel { dram_bytes: 16.0 * 1024.0, ..aware };
    for s in &choice.curve {
        let bytes = 4.125 * s.cells as f64 + 4.0 * s.n_m as f64;
        let beyond = (bytes - 16.0 * 1024.0).max(0.0);
        let expected = aware.cost(s.cells, s.n_m, tris.len()) + 0.1 * 8.0 * beyond / tris.len() as f64;
        assert!((dram.cost(s.cells, s.n_m, tris.len()) - expected).abs() < 1e-9, "{s:?}");
    }
    let coarser = resolution::choose(&tris, &b, Resolution::Auto, &dram, InsertMode::BoundingBox, true);
    assert!(m(&coarser) < m(&choice), "{:?} vs {:?}", coarser.resolution, choice.resolution);
    // A tiny scene's grid fits in the cache: the memory-aware choice is no coarser than the
    // survey's there (the Cornell box's 36 triangles went to 3³ cells without the cache).
    let tiny: Vec<[Vec3; 3]> = tris.iter().step_by((tris.len() / 36).max(1)).take(36).copied().collect();
    let tb = gridrt_grid::triangle_bounds(&tiny);
    let pick = |m: &CostModel| resolution::choose(&tiny, &tb, Resolution::Auto, m, InsertMode::BoundingBox, true);
    assert!(
        m(&pick(&aware)) > m(&pick(&uncached)),
        "{:?} vs {:?}",
        pick(&aware).resolution,
        pick(&uncached).resolution
    );
    let survey = resolution::choose(&tris, &b, Resolution::Auto, &model, InsertMode::BoundingBox, true);
    assert!(m(&choice) < m(&survey), "{:?} vs {:?}", choice.resolution, survey.resolution);
}

/// Above `EXACT_COUNT_LIMIT` triangles guess-and-check estimates N_m from a sample of the small
/// and mid-size triangles (large ones always counted), for both insertion modes: the estimate stays within 2% of the exact count on scenes whose
/// N_m is dominated by small triangles (particles), by many mid-size ones (mountain, slivers),
/// and by a few huge ones next to many tiny ones (teapot in a stadium, plus a big box).
#[test]
fn guess_and_check_estimate_tracks_the_exact_count() {
    let mut stadium = tris_of(SceneKind::TeapotInStadium, 3);
    stadium.extend(tris_of(SceneKind::Particles, 60_000));
    let scenes = [
        ("particles", tris_of(SceneKind::Particles, 120_000)),
        ("mountain", tris_of(SceneKind::Mountain, 8)),
        ("slivers", tris_of(SceneKind::Slivers, 50_000)),
        ("stadium+particles", stadium),
    ];
    for (name, tris) in &scenes {
        assert!(tris.len() > resolution::EXACT_COUNT_LIMIT, "{name}: {} triangles", tris.len());
        let b = triangle_bounds(tris);
        let res: Vec<[u32; 3]> = [40, 80, 160].iter().map(|&m| resolution::cubic_m(&b, m)).collect();
        // Exact insertion's reference counts cost a build each: checked on the two scenes of
        // small triangles (its sample only covers small ones).
        let modes: &[InsertMode] =
            if matches!(*name, "particles" | "mountain") { &InsertMode::ALL } else { &[InsertMode::BoundingBox] };
        for &mode in modes {
            let (est, counted) = resolution::count_refs_curve(tris, &b, &res, mode, true);
            assert!(counted < tris.len(), "{name}: nothing was sampled");
            let (serial, _) = resolution::count_refs_curve(tris, &b, &res, mode, false);
            assert_eq!(est, serial, "{name} {mode:?}: the estimate depends on the thread split");
            // With the widest extents per run (the bounds pass's, computed here whatever the
            // scene's size), runs of small triangles are not read but for their sample: the
            // same counts and the same choice.
            let extents = resolution::ChunkExtents(
                tris.chunks(resolution::COUNT_CHUNK)
                    .map(|c| gridrt_scene::Aabb::of_triangles_and_widest(c).1)
                    .collect(),
            );
            for parallel in [true, false] {
                let (with, _) = resolution::count_refs_curve_with(tris, &b, Some(&extents), &res, mode, parallel);
                assert_eq!(with, est, "{name} {mode:?}: the extents changed the counts");
                let model = CostModel::memory_aware();
                assert_eq!(
                    resolution::choose_with(
                        tris,
                        &b,
                        Some(&extents),
                        Resolution::Auto,
                        &model,
                        InsertMode::BoundingBox,
                        parallel
                    ),
                    resolution::choose(tris, &b, Resolution::Auto, &model, InsertMode::BoundingBox, parallel),
                    "{name}"
                );
            }
            for (r, e) in res.iter().zip(&est) {
                let exact = resolution::count_refs(tris, &b, *r, mode, true);
                let err = (*e as f64 / exact as f64 - 1.0).abs();
                assert!(err < 0.02, "{name} {mode:?} at {r:?}: estimate {e} vs exact {exact} ({:.2}%)", err * 100.0);
            }
        }
    }
}

/// The bounds pass with extents: the same bounds as the scene crate's, and each run's widest
/// extent per axis bounds every triangle of the run.
#[test]
fn bounds_pass_extents_bound_every_triangle_of_their_run() {
    for tris in
        [tris_of(SceneKind::Mountain, 7), tris_of(SceneKind::Particles, 30_000), tris_of(SceneKind::Slivers, 100)]
    {
        for parallel in [true, false] {
            let (b, e) = gridrt_grid::triangle_bounds_and_extents(&tris, parallel);
            assert_eq!(b, gridrt_scene::Aabb::of_triangles(&tris));
            assert_eq!(b, gridrt_grid::triangle_bounds_with(&tris, parallel));
            assert_eq!(e.0.len(), tris.len().div_ceil(resolution::COUNT_CHUNK));
            for (w, run) in e.0.iter().zip(tris.chunks(resolution::COUNT_CHUNK)) {
                let widest = |t: &[Vec3; 3]| t[0].max(t[1]).max(t[2]) - t[0].min(t[1]).min(t[2]);
                assert!(run.iter().all(|t| widest(t).cmple(*w).all()));
                assert!(run.iter().any(|t| widest(t).x == w.x));
            }
        }
    }
}

/// Long slivers: the finest samples of the cost model's interval need more references than a
/// grid may hold; the auto resolution takes the best buildable sample, and the grid builds.
#[test]
fn auto_resolution_never_exceeds_the_reference_limit() {
    let tris = tris_of(SceneKind::Slivers, 20_000);
    let b = triangle_bounds(&tris);
    let model = CostModel { max_cells_per_triangle: 1e4, max_cells: 1 << 27, ..CostModel::default() };
    let choice = resolution::choose(&tris, &b, Resolution::Auto, &model, InsertMode::BoundingBox, true);
    let limit = gridrt_grid::build::MAX_REFS;
    assert!(choice.curve.iter().any(|s| s.n_m > limit), "the test needs unbuildable samples: {:?}", choice.curve);
    let chosen = choice.curve.iter().find(|s| s.resolution == choice.resolution).unwrap();
    assert!(chosen.n_m <= limit, "{chosen:?}");
    assert!(choice.curve.iter().filter(|s| s.n_m <= limit).all(|s| s.cost >= chosen.cost));
    assert_eq!(model.best_sample(&choice.curve).unwrap(), chosen);
}

/// Guess-and-check's ties: the least T(m) without a tolerance; with one, each next coarser
/// sample within it of the least (the whole flat basin), never a distant coarser dip past a
/// sample above the bound, and never an unbuildable sample.
#[test]
fn ties_go_to_the_coarser_grid_within_the_basin() {
    let sample = |m: u32, cost: f64, n_m: u64| resolution::CostSample {
        m: m as f64,
        resolution: [m; 3],
        cells: (m as u64).pow(3),
        n_m,
        mu: 0.0,
        cost,
    };
    // In increasing m: a dip at 4, a bump at 6, a basin 8..12 with its least at 12.
    let curve = [
        sample(4, 100.4, 10),
        sample(6, 110.0, 10),
        sample(8, 102.5, 10),
        sample(10, 101.0, 10),
        sample(12, 100.0, 10),
        sample(14, 104.0, 10),
    ];
    let res =
        |t: f64| CostModel { tie_tolerance: t, ..CostModel::memory_aware() }.best_sample(&curve).unwrap().resolution[0];
    assert_eq!(res(0.0), 12, "no tolerance: the least T(m)");
    assert_eq!(res(0.005), 12, "the next coarser sample is 1% above");
    assert_eq!(res(0.02), 10);
    assert_eq!(res(0.03), 8, "the whole basin");
    assert_eq!(res(0.2), 4, "a tolerance over the bump reaches the dip");
    assert_eq!(CostModel::default().tie_tolerance, 0.0, "the survey's model takes the least T(m)");
    assert_eq!(CostModel::memory_aware().tie_tolerance, resolution::MEMORY_AWARE_TIE_TOLERANCE);
    // A coarser sample that cannot be built is not a tie partner, and a least T(m) that cannot be
    // built is not the least.
    let limit = gridrt_grid::build::MAX_REFS;
    let mut blocked = curve;
    blocked[3].n_m = limit + 1;
    let t3 = CostModel { tie_tolerance: 0.03, ..CostModel::memory_aware() };
    assert_eq!(t3.best_sample(&blocked).unwrap().resolution[0], 12);
    blocked[4].n_m = limit + 1;
    assert_eq!(t3.best_sample(&blocked).unwrap().resolution[0], 4, "least buildable: 4 (100.4)");
    let none: Vec<_> = curve.iter().map(|s| resolution::CostSample { n_m: limit + 1, ..*s }).collect();
    assert_eq!(t3.best_sample(&none).unwrap().resolution[0], 4, "nothing buildable: the coarsest");
    assert!(t3.best_sample(&[]).is_none());
}

/// Hierarchies over shapes whose sub-grids would multiply references: needles (the slivers
/// scene: long thin triangles whose boxes span much of the scene), copies of one triangle, and a
/// fan of triangles sharing a vertex. Without a bound, the two-level grid's every-cell rule put
/// each of a top cell's n needles in all of its ~1.2·n leaf cells, the cost test accepted a
/// sub-grid of 400 references per copy, and the fan's middle cells stayed as full as their
/// parents at every depth. Every subtree now holds at most
/// [`multires::SUBTREE_REFS_PER_TRIANGLE`] references per triangle of its top cell, so the
/// hierarchy holds at most that many times the top grid's references; the default two-level
/// grid subdivides fewer needle cells than the every-cell rule; and every grid traces as brute
/// force does.
#[test]
fn hierarchies_keep_their_references_within_the_budget() {
    use gridrt_grid::multires::{self, MultiresOptions};
    use gridrt_grid::trace::TraceOptions;
    use gridrt_grid::twolevel::TwoLevelOptions;
    use gridrt_grid::{GridConfig, GridKind, structure};

    let needles = procedural::generate(SceneKind::Slivers, 3000, 5);
    let copies: Vec<[Vec3; 3]> = (0..2000)
        .map(|_| [Vec3::ZERO, Vec3::X, Vec3::Y])
        .chain((0..500).map(|i| {
            let c = Vec3::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32) * 0.1 + Vec3::splat(0.05);
            [c, c + Vec3::new(0.01, 0.0, 0.0), c + Vec3::new(0.0, 0.01, 0.005)]
        }))
        .collect();
    let fan: Vec<[Vec3; 3]> = (0..5000)
        .map(|i| {
            let a = |k: u32| {
                let t = k as f32 / 5000.0 * std::f32::consts::TAU;
                Vec3::new(t.cos(), t.sin(), 0.1 * (7.0 * t).sin())
            };
            [Vec3::ZERO, a(i), a(i + 1)]
        })
        .collect();
    let rays_of = |tris: &[[Vec3; 3]], seed: u64| {
        let mesh = gridrt_scene::Mesh {
            positions: tris.iter().flatten().copied().collect(),
            indices: (0..tris.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
        };
        super::common::mixed_rays(&mesh, &[], 3000, seed)
    };
    let scenes = [
        ("needles", needles.mesh.triangles(), rays_of(&needles.mesh.triangles(), 11)),
        ("copies", copies.clone(), rays_of(&copies, 12)),
        ("fan", fan.clone(), rays_of(&fan, 13)),
    ];
    for (name, tris, rays) in &scenes {
        let (expected, _) = super::common::reference(tris, rays);
        for insert in InsertMode::ALL {
            let mut twolevel_nodes = Vec::new();
            for (kind, every_cell) in
                [(GridKind::Multires, false), (GridKind::TwoLevel, false), (GridKind::TwoLevel, true)]
            {
                let cfg = GridConfig {
                    kind,
                    build: BuildOptions { insert, parallel: true },
                    twolevel: TwoLevelOptions { every_cell, ..TwoLevelOptions::default() },
                    multires: MultiresOptions::default(),
                    ..GridConfig::default()
                };
                let (grid, report) = structure::build(tris, &cfg).unwrap();
                let what = format!("{name} {kind} {insert:?} every cell {every_cell}");
                let (hits, _) =
                    grid.trace_batch(tris, rays, TraceOptions { mailbox: true, ..Default::default() }, true);
                super::common::assert_same_hits(&what, rays, &expected, &hits);
                let top = report.stats.resolution;
                let (flat, _, _) = build_flat(
                    tris,
                    Resolution::Explicit(top),
                    &CostModel::default(),
                    BuildOptions { insert, parallel: true },
                )
                .unwrap();
                let bound = multires::SUBTREE_REFS_PER_TRIANGLE * flat.refs.len() as f64;
                println!("{what}: {} references, {} nodes, bound {bound}", report.stats.refs, report.stats.nodes);
                assert!(report.stats.refs as f64 <= bound, "{what}: {} references", report.stats.refs);
                if kind == GridKind::TwoLevel {
                    twolevel_nodes.push(report.stats.nodes);
                }
            }
            if *name == "needles" && insert == InsertMode::BoundingBox {
                assert!(twolevel_nodes[0] < twolevel_nodes[1], "{name}: nodes {twolevel_nodes:?}");
            }
        }
    }
}

/// Each macrocell is occupied exactly when a fine cell of its block is, for every candidate A
/// (given, and the cost model's choice) on resolutions that are not multiples of A.
#[test]
fn macro_occupancy_is_that_of_its_fine_cells() {
    use glam::UVec3;
    use gridrt_grid::macrocell::{MACRO_SIZES, MacrocellGrid};
    for (kind, size) in [(SceneKind::Particles, 800), (SceneKind::Slivers, 300), (SceneKind::Mountain, 4)] {
        let tris = tris_of(kind, size);
        let bounds = gridrt_scene::Aabb::of_triangles(&tris);
        for res in [[37, 5, 19], [16, 16, 16], [1, 70, 3]] {
            let given = MACRO_SIZES.iter().map(|&a| Some(a)).chain([Some(1), Some(32), None]);
            for a in given {
                let opts = BuildOptions { insert: InsertMode::BoundingBox, parallel: true };
                let (g, _) = MacrocellGrid::build(&tris, &bounds, res, a, opts, &mut PhaseTimes::default()).unwrap();
                let mut want = vec![false; g.occupancy.len() * 32];
                let r = g.fine.geom.res;
                for z in 0..r.z {
                    for y in 0..r.y {
                        for x in 0..r.x {
                            let c = UVec3::new(x, y, z);
                            if g.fine.is_occupied(g.fine.geom.cell_index(c)) {
                                let m = c / g.a;
                                want[(m.x + g.macro_res.x * (m.y + g.macro_res.y * m.z)) as usize] = true;
                            }
                        }
                    }
                }
                for (k, &w) in want.iter().enumerate() {
                    assert_eq!(g.occupancy[k / 32] >> (k % 32) & 1 != 0, w, "{kind:?} {res:?} A {} macrocell {k}", g.a);
                }
            }
        }
    }
}
