//! The exact traversals visit exactly the cells the ray segment crosses, in order of increasing
//! t; Bresenham misses some. Reference: an f64 slab test of the segment against every cell.

use glam::{DVec3, UVec3, Vec3};
use gridrt_grid::GridGeometry;
use gridrt_grid::geometry::GridRay;
use gridrt_grid::ray::PreparedRay;
use gridrt_grid::traversal::{Traversal, Walker};
use gridrt_scene::rng::Rng;
use gridrt_scene::{Aabb, Ray};

/// Tolerance in cells: walkers may disagree with exact arithmetic by this much (Liu's fixed
/// point on these small grids is ≤ 32·2^-21 ≈ 1.5e-5).
const TOL: f64 = 1e-4;

/// Segment [t0, t1] of `r` against box [lo, hi] (grid space, f64): the overlap interval.
fn slab(r: &GridRay, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let o = r.o.as_dvec3();
    let d = r.d.as_dvec3();
    let (mut t0, mut t1) = (r.t0 as f64, r.t1 as f64);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return None;
            }
            continue;
        }
        let ta = (lo[a] - o[a]) / d[a];
        let tb = (hi[a] - o[a]) / d[a];
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    (t0 <= t1).then_some((t0, t1))
}

#[derive(Default, Debug)]
struct Counts {
    rays: usize,
    visited: usize,
    missed: usize,
}

/// Checks one walk; returns (cells the walk should have visited, cells it missed).
fn check_walk(kind: Traversal, r: &GridRay, res: UVec3, label: &str) -> (usize, usize) {
    let steps: Vec<_> = Walker::new(kind, r, res).collect();
    let cells: Vec<UVec3> = steps.iter().map(|s| s.cell).collect();
    let mut must = Vec::new();
    for z in 0..res.z {
        for y in 0..res.y {
            for x in 0..res.x {
                let c = UVec3::new(x, y, z);
                let lo = c.as_dvec3();
                if slab(r, lo + DVec3::splat(TOL), lo + DVec3::splat(1.0 - TOL)).is_some() {
                    must.push(c);
                }
            }
        }
    }
    let missed = must.iter().filter(|c| !cells.contains(c)).count();
    if !kind.is_exact() {
        return (must.len(), missed);
    }
    assert!(
        missed == 0,
        "{label}: {kind} missed {missed} of {} crossed cells; ray {r:?}; visited {cells:?}; must {must:?}",
        must.len()
    );
    let mut prev_enter = f64::NEG_INFINITY;
    for (i, s) in steps.iter().enumerate() {
        let lo = s.cell.as_dvec3();
        let Some((t_in, t_out)) = slab(r, lo - DVec3::splat(TOL), lo + DVec3::splat(1.0 + TOL)) else {
            panic!(
                "{label}: {kind} visited cell {:?} the segment does not touch; ray {r:?}; visited {cells:?}",
                s.cell
            );
        };
        // Increasing t: each cell is entered no earlier than the previous one (tolerance in t).
        let tol_t = TOL / r.d.as_dvec3().abs().max_element();
        assert!(
            t_in + 2.0 * tol_t >= prev_enter,
            "{label}: {kind} out of order at step {i}; ray {r:?}; visited {cells:?}"
        );
        prev_enter = t_in;
        assert!(
            (s.t_exit as f64) <= t_out + 4.0 * tol_t + 1e-6 * t_out.abs(),
            "{label}: {kind} reports t_exit {} beyond the cell's exit {t_out} at step {i}; ray {r:?}",
            s.t_exit
        );
        if i > 0 {
            let d = s.cell.as_ivec3() - cells[i - 1].as_ivec3();
            assert_eq!(
                d.abs().element_sum(),
                1,
                "{label}: {kind} jumped from {:?} to {:?}; ray {r:?}",
                cells[i - 1],
                s.cell
            );
        }
        assert!(!cells[..i].contains(&s.cell), "{label}: {kind} visited {:?} twice; ray {r:?}", s.cell);
    }
    (must.len(), 0)
}

/// Ray families on a grid: random, axis-parallel, zero components, corners, edges, inside,
/// outside, missing, unnormalised, clipped.
fn adversarial_rays(geom: &GridGeometry, rng: &mut Rng, count: usize) -> Vec<Ray> {
    let lattice = |rng: &mut Rng| {
        let i = UVec3::new(
            rng.below(geom.res.x as u64 + 1) as u32,
            rng.below(geom.res.y as u64 + 1) as u32,
            rng.below(geom.res.z as u64 + 1) as u32,
        );
        geom.min + i.as_vec3() * geom.cell
    };
    let ext = geom.max - geom.min;
    let inside = |rng: &mut Rng| geom.min + Vec3::new(rng.f32(), rng.f32(), rng.f32()) * ext;
    let around = |rng: &mut Rng| geom.min - ext + Vec3::new(rng.f32(), rng.f32(), rng.f32()) * ext * 3.0;
    let mut rays = Vec::with_capacity(count);
    for i in 0..count {
        let (o, d) = match i % 10 {
            0 => (inside(rng), rng.unit_vector()),
            1 => (around(rng), inside(rng) - around(rng)),
            2 => {
                let a = rng.below(3) as usize;
                let mut d = Vec3::ZERO;
                d[a] = if rng.f32() < 0.5 { 1.0 } else { -1.0 };
                // Axis-parallel, often exactly along a lattice line or plane.
                let o = if i % 20 == 2 { lattice(rng) } else { around(rng) };
                (o, d)
            }
            3 => {
                let mut d = rng.unit_vector();
                d[rng.below(3) as usize] = 0.0;
                (if i % 20 == 3 { lattice(rng) } else { inside(rng) }, d)
            }
            4 => {
                // Through a cell corner (lattice point), from anywhere.
                let o = around(rng);
                (o, lattice(rng) - o)
            }
            5 => {
                // From a corner along a diagonal: passes through corners again and again.
                let s = |rng: &mut Rng| if rng.f32() < 0.5 { -1.0 } else { 1.0 };
                (lattice(rng), Vec3::new(s(rng), s(rng), s(rng)) * geom.cell)
            }
            6 => {
                // Through a point on a cell edge.
                let mut p = lattice(rng);
                let a = rng.below(3) as usize;
                p[a] += rng.f32() * geom.cell[a];
                let o = around(rng);
                (o, p - o)
            }
            7 => (around(rng), rng.unit_vector()), // often misses the grid
            8 => (inside(rng), rng.unit_vector() * 10f32.powf(rng.range(-4.0, 4.0))),
            _ => (inside(rng), -rng.unit_vector()),
        };
        let d = if d == Vec3::ZERO { Vec3::X } else { d };
        let (tmin, tmax) = if i % 3 == 0 {
            let len = ext.length() / d.length();
            let a = rng.range(-0.5, 1.5) * len;
            (a, a + rng.range(0.0, 1.0) * len)
        } else {
            (0.0, f32::INFINITY)
        };
        rays.push(Ray::new(o, d, tmin, tmax));
    }
    rays
}

#[test]
fn exact_traversals_visit_exactly_the_crossed_cells() {
    let mut rng = Rng::new(7);
    let mut counts: std::collections::HashMap<Traversal, Counts> = Default::default();
    let mut clipped = 0;
    for g in 0..60 {
        let res = if g < 4 {
            [[1, 1, 1], [1, 7, 1], [16, 16, 16], [32, 3, 9]][g]
        } else {
            [1 + rng.below(12) as u32, 1 + rng.below(12) as u32, 1 + rng.below(12) as u32]
        };
        let lo = Vec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
        let hi = lo + Vec3::new(rng.range(0.5, 8.0), rng.range(0.5, 8.0), rng.range(0.5, 8.0));
        let geom = GridGeometry::new(&Aabb { min: lo, max: hi }, res);
        for (i, ray) in adversarial_rays(&geom, &mut rng, 400).iter().enumerate() {
            let Some(pr) = PreparedRay::new(ray) else { continue };
            let Some(gr) = geom.clip(&pr) else { continue };
            clipped += 1;
            for kind in Traversal::ALL {
                let (must, missed) = check_walk(kind, &gr, geom.res, &format!("grid {g} {res:?} ray {i}"));
                let c = counts.entry(kind).or_default();
                c.rays += 1;
                c.visited += must;
                c.missed += missed;
            }
        }
    }
    assert!(clipped > 10_000, "too few rays hit the grids: {clipped}");
    let b = &counts[&Traversal::Bresenham];
    println!(
        "naive Bresenham missed {} of {} crossed cells ({:.1}%) over {} rays",
        b.missed,
        b.visited,
        100.0 * b.missed as f64 / b.visited as f64,
        b.rays
    );
    // Bresenham visits one cell per driving-axis slice, so on diagonal rays it must miss cells.
    assert!(b.missed as f64 > 0.05 * b.visited as f64, "Bresenham should miss a sizeable share of cells: {b:?}");
}

#[test]
fn bresenham_misses_cells_on_a_diagonal() {
    // The survey's Figure 1: a 45° ray across an 8×8×1 grid crosses 15 cells; Bresenham sees 8.
    let geom = GridGeometry::new(&Aabb { min: Vec3::ZERO, max: Vec3::new(8.0, 8.0, 1.0) }, [8, 8, 1]);
    let ray = Ray::new(Vec3::new(-1.0, -0.5, 0.5), Vec3::new(1.0, 1.0, 0.0), 0.0, f32::INFINITY);
    let gr = geom.clip(&PreparedRay::new(&ray).unwrap()).unwrap();
    let n_b = Walker::new(Traversal::Bresenham, &gr, geom.res).count();
    for kind in Traversal::EXACT {
        let n = Walker::new(kind, &gr, geom.res).count();
        assert_eq!(n, 15, "{kind}");
    }
    assert_eq!(n_b, 8);
}

/// `walk` (every structure's loop; Amanatides–Woo fused into one loop over linear addresses)
/// visits each walker's cells with their addresses and exits, bit for bit, and stops where it
/// is told to.
#[test]
fn walk_matches_the_walkers_iterators() {
    use gridrt_grid::traversal::walk;
    let mut rng = Rng::new(11);
    let mut compared = 0;
    for g in 0..40 {
        let res = [1 + rng.below(20) as u32, 1 + rng.below(20) as u32, 1 + rng.below(20) as u32];
        let lo = Vec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
        let hi = lo + Vec3::new(rng.range(0.5, 8.0), rng.range(0.5, 8.0), rng.range(0.5, 8.0));
        let geom = GridGeometry::new(&Aabb { min: lo, max: hi }, res);
        for (i, ray) in adversarial_rays(&geom, &mut rng, 300).iter().enumerate() {
            let Some(pr) = PreparedRay::new(ray) else { continue };
            let Some(gr) = geom.clip(&pr) else { continue };
            for kind in Traversal::ALL {
                let want: Vec<(UVec3, usize, u32)> = Walker::new(kind, &gr, geom.res)
                    .map(|s| (s.cell, geom.cell_index(s.cell), s.t_exit.to_bits()))
                    .collect();
                let mut got = Vec::new();
                let stopped = walk(kind, &gr, geom.res, |c, a, t| {
                    got.push((c, a, t.to_bits()));
                    false
                });
                assert!(!stopped);
                assert_eq!(got, want, "{kind} grid {g} {res:?} ray {i}: {ray:?}");
                let stop = i % want.len().max(1);
                let mut seen = 0;
                let stopped = walk(kind, &gr, geom.res, |_, _, _| {
                    seen += 1;
                    seen > stop
                });
                assert_eq!(seen, (stop + 1).min(want.len()), "{kind} grid {g} ray {i}: early stop");
                assert_eq!(stopped, stop < want.len(), "{kind} grid {g} ray {i}: stop reported");
                compared += 1;
            }
        }
    }
    assert!(compared > 20_000, "too few walks compared: {compared}");
}

/// The walk over blocks (macrocells' hierarchical DDA, `AmanatidesWoo::walk_blocks`) visits
/// the flat walk's cells, addresses and exits bit for bit, except that each run of cells in
/// empty blocks is visited at its first cell only; the count it returns adds each further
/// empty block of the run. Blocks of 2 to 32 cells per edge (16 and 32 take the wall count's
/// SIMD lanes more than once), grids whose last blocks are cut short, random empty blocks, the adversarial rays (lattice corners,
/// diagonals through corners, axis-parallel rays on walls: ties between axes), clipped
/// segments, and walks that stop early.
#[test]
fn walk_blocks_is_the_flat_walk_less_empty_blocks() {
    use gridrt_grid::traversal::Visit;
    use gridrt_grid::traversal::amanatides_woo::AmanatidesWoo;
    let mut rng = Rng::new(29);
    let (mut compared, mut skipped_runs) = (0, 0);
    for g in 0..60 {
        let log2 = 1 + rng.below(5) as u32;
        let edge = 1u32 << log2;
        let blocks = UVec3::new(1 + rng.below(4) as u32, 1 + rng.below(4) as u32, 1 + rng.below(4) as u32);
        // Every other grid's last blocks cut short by its end.
        let cut = |rng: &mut Rng| if g % 2 == 1 { rng.below(edge as u64) as u32 } else { 0 };
        let res = (blocks * edge - UVec3::new(cut(&mut rng), cut(&mut rng), cut(&mut rng))).max(UVec3::ONE);
        let lo = Vec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
        // Power-of-two cell sizes on some grids: more crossings tie exactly.
        let size = if g % 3 == 0 {
            res.as_vec3() * 0.25
        } else {
            Vec3::new(rng.range(0.5, 8.0), rng.range(0.5, 8.0), rng.range(0.5, 8.0))
        };
        let geom = GridGeometry::new(&Aabb { min: lo, max: lo + size }, res.to_array());
        assert_eq!(geom.res, res);
        let empty_share = [0.3, 0.7, 0.95][g % 3];
        let empty: Vec<bool> = (0..blocks.element_product()).map(|_| rng.f32() < empty_share).collect();
        let block_empty = |b: UVec3| empty[(b.x + blocks.x * (b.y + blocks.y * b.z)) as usize];
        for (i, ray) in adversarial_rays(&geom, &mut rng, 200).iter().enumerate() {
            let Some(pr) = PreparedRay::new(ray) else { continue };
            let Some(gr) = geom.clip(&pr) else { continue };
            // The flat walk, each run of cells in empty blocks cut to its first cell, and the
            // count: the cells kept plus the further blocks of each run.
            let mut want = Vec::new();
            let (mut count, mut run_block) = (0u32, None);
            for s in Walker::new(Traversal::AmanatidesWoo, &gr, geom.res) {
                let b = s.cell >> log2;
                if !block_empty(b) {
                    run_block = None;
                } else if run_block.is_some() {
                    if run_block != Some(b) {
                        count += 1;
                        run_block = Some(b);
                    }
                    continue;
                } else {
                    run_block = Some(b);
                    skipped_runs += 1;
                }
                want.push((s.cell, geom.cell_index(s.cell), s.t_exit.to_bits()));
                count += 1;
            }
            let mut got = Vec::new();
            let (stopped, visits) = AmanatidesWoo::new(&gr, geom.res).walk_blocks(log2, block_empty, |c, a, t| {
                got.push((c, a, t.to_bits()));
                if block_empty(c >> log2) { Visit::LeaveBlock } else { Visit::Next }
            });
            assert!(!stopped);
            assert_eq!(got, want, "grid {g} {res:?} edge {edge} ray {i}: {ray:?}");
            assert_eq!(visits, count, "grid {g} {res:?} edge {edge} ray {i}: visits counted");
            // Stopped at a visit: the same cells up to it.
            let stop = i % want.len().max(1);
            let mut seen = 0;
            let (stopped, _) = AmanatidesWoo::new(&gr, geom.res).walk_blocks(log2, block_empty, |c, _, _| {
                seen += 1;
                if seen > stop {
                    Visit::Stop
                } else if block_empty(c >> log2) {
                    Visit::LeaveBlock
                } else {
                    Visit::Next
                }
            });
            assert_eq!(seen, (stop + 1).min(want.len()), "grid {g} ray {i}: early stop");
            assert_eq!(stopped, stop < want.len(), "grid {g} ray {i}: stop reported");
            compared += 1;
        }
    }
    assert!(compared > 5_000 && skipped_runs > 2_000, "too few walks: {compared}, {skipped_runs} runs of empty blocks");
}
