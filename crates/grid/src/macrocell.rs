//! Macrocells (Parker et al. 1999): a coarse occupancy grid over A×A×A blocks of a flat grid.
//!
//! An empty macrocell is crossed in one step, and only inside an occupied one does the ray walk
//! fine cells. Macrocells start at multiples of A fine cells (the fine grid keeps the resolution
//! it is given; the last macrocell on an axis may be cut short by the grid's end), so their walls
//! are fine walls; A is a power of two, so the macro grid-space ray is the fine one scaled by 1/A
//! without rounding. With Amanatides–Woo the walk is one hierarchical DDA over the fine cells
//! ([`AmanatidesWoo::walk_blocks`]); with the other walkers, the macro grid's walk and in each
//! occupied macrocell a walk of its fine cells.
//!
//! # Layout (GPU-ready: flat arrays, indices only)
//! - the fine grid, a [`FlatGrid`] (occupancy words, an offset per occupied cell, `refs`; the
//!   GPU reads its M + 1 table, [`FlatGrid::cell_table`]);
//! - `occupancy`: one u32 word per 32 macrocells, bit `i % 32` of word `i / 32` set when
//!   macrocell `i` (x fastest) holds at least one reference.
//!
//! # Choosing A
//! By default A is chosen by the cost model: a ray crossing m fine cells crosses about m/A
//! macrocells and, in the fraction f_A of them that is occupied, about A fine cells each, so the
//! stepping cost is ≈ (m/A + W·f_A·m)·Tstep (the intersection term does not depend on A), where
//! a fine cell's step in an occupied macrocell weighs W = [`FINE_STEP_WEIGHT`] macrocell steps:
//! it reads the fine and the macro occupancy bits, a macrocell's step only the macro ones. f_A is
//! counted exactly on the fine grid for A ∈ {2, 4, 8, 16}; the A minimising 1/A + W·f_A wins.

use glam::{UVec3, Vec3};
use gridrt_scene::{Aabb, Hit, Ray};
use serde::{Deserialize, Serialize};

use crate::BuildError;
use crate::build::{BuildOptions, PhaseTimes};
use crate::cell_plane::CellRay;
use crate::flat::{FlatGrid, WORD_CELLS};
use crate::geometry::{GridGeometry, GridRay, linear_index};
use crate::stats::RayStats;
use crate::trace::TraceOptions;
use crate::trace::closest_hit::{ClosestHit, closest_hit};
use crate::traversal::amanatides_woo::AmanatidesWoo;
use crate::traversal::{Traversal, Visit, walk_counted};

/// What a fine cell's step in an occupied macrocell costs in macrocell steps, for the choice of
/// A (see the module doc). Measured (2026-12-05, one thread): with 1, the bunny's grid chose
/// A = 8, 0.91× the speed of A = 4 on camera rays (the engine's 8 too, within noise of 4); with
/// 1.25 the bunny, igea, the dragon, the armadillo, the engine and Sponza get 4 and the teapot 2,
/// each the fastest of a sweep over 2 to 16 or within 4% of it.
pub const FINE_STEP_WEIGHT: f64 = 1.25;

/// Macrocell sizes the cost model chooses among.
pub const MACRO_SIZES: [u32; 4] = [2, 4, 8, 16];

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MacrocellGrid {
    pub fine: FlatGrid,
    /// Fine cells per macrocell edge (a power of two).
    pub a: u32,
    /// Macro grid resolution (fine resolution / A).
    pub macro_res: UVec3,
    /// One bit per macrocell, x fastest.
    pub occupancy: Vec<u32>,
}

/// Occupancy figures for one candidate A.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MacroSample {
    pub a: u32,
    pub macro_cells: u64,
    pub occupied: u64,
    /// 1/A + W·f_A: the relative stepping cost the choice minimises.
    pub cost: f64,
}

impl MacrocellGrid {
    /// Builds the fine grid at `res` and the macro occupancy. `a = None` lets the cost model
    /// choose A (see the module doc) from the fine grid itself: one build whatever A.
    /// `bounds`: of `tris`.
    pub fn build(
        tris: &[[Vec3; 3]],
        bounds: &Aabb,
        res: [u32; 3],
        a: Option<u32>,
        opts: BuildOptions,
        times: &mut PhaseTimes,
    ) -> Result<(MacrocellGrid, Vec<MacroSample>), BuildError> {
        if let Some(a) = a {
            check_macro_size(a)?;
        }
        let fine = FlatGrid::build(tris, GridGeometry::new(bounds, res), opts, times)?;
        let (a, samples, (macro_res, occupancy)) = match a {
            Some(a) => {
                let mut bits = times.record("occupancy", || occupancies(&fine, &[a]));
                (a, Vec::new(), bits.remove(0))
            }
            None => times.record("macro-size", || {
                // Every candidate's bits in one pass; the chosen one's are kept.
                let mut bits = occupancies(&fine, &MACRO_SIZES);
                let samples: Vec<MacroSample> = MACRO_SIZES
                    .iter()
                    .zip(&bits)
                    .map(|(&a, (macro_res, occ))| MacroSample::from_occupancy(a, *macro_res, occ))
                    .collect();
                let chosen = best_macro_sample(&samples);
                (samples[chosen].a, samples, bits.swap_remove(chosen))
            }),
        };
        Ok((MacrocellGrid { fine, a, macro_res, occupancy }, samples))
    }

    pub fn memory_bytes(&self) -> u64 {
        self.fine.memory_bytes() + self.occupancy.len() as u64 * 4
    }

    #[inline]
    pub fn occupied(&self, m: UVec3) -> bool {
        self.occupied_at(linear_index(m, self.macro_res))
    }

    /// Whether the macrocell at linear address `i` holds references.
    #[inline]
    pub fn occupied_at(&self, i: usize) -> bool {
        self.occupancy[i / 32] & (1 << (i % 32)) != 0
    }

    pub fn occupied_count(&self) -> u64 {
        self.occupancy.iter().map(|w| w.count_ones() as u64).sum()
    }

    /// Closest hit. Amanatides–Woo: one walk of the fine cells that crosses empty macrocells on
    /// the macro grid's walk ([`AmanatidesWoo::walk_blocks`]); the other walkers: the macro walk,
    /// and a walk of the fine cells inside each occupied macrocell.
    pub fn trace(&self, tris: &[[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> (Hit, RayStats) {
        let traversal = opts.traversal;
        if traversal == Traversal::AmanatidesWoo {
            return closest_hit(tris, ray, opts, |search| {
                let Some(fine_ray) = self.fine.geom.clip(&search.ray) else { return };
                let cr = self.fine.cell_ray(&fine_ray);
                let walk = AmanatidesWoo::new(&fine_ray, self.fine.geom.res);
                let empty = |m: UVec3| !self.occupied(m);
                let (_, cells) = walk.walk_blocks(self.log2_edge(), empty, |c, index, t_exit| {
                    self.visit(search, cr.as_ref(), c, index, t_exit)
                });
                search.visit_cells(cells);
            });
        }
        closest_hit(tris, ray, opts, |search| {
            let Some(fine_ray) = self.fine.geom.clip(&search.ray) else { return };
            let macro_ray = self.macro_ray(&fine_ray);
            let mut t_enter = fine_ray.t0;
            let (_, cells) = walk_counted(traversal, &macro_ray, self.macro_res, |m, maddr, m_exit| {
                // An occupied macrocell's fine walk is a call, keeping the macro walk's loop
                // small (most macrocells are empty).
                let entered = std::mem::replace(&mut t_enter, m_exit);
                if self.occupied_at(maddr) && self.walk_block(m, &fine_ray, (entered, m_exit), traversal, search) {
                    return true;
                }
                search.done_at(m_exit)
            });
            search.visit_cells(cells);
        })
    }

    /// A fine cell's visit in the walk over macrocells: its tests when it holds triangles (unless
    /// `ray`'s segment misses its slab, [`crate::cell_plane`]), a jump out of its macrocell when
    /// that is empty.
    #[inline]
    pub fn visit(&self, search: &mut ClosestHit, ray: Option<&CellRay>, c: UVec3, index: usize, t_exit: f32) -> Visit {
        if self.fine.is_occupied(index) {
            if self.fine.test_occupied(search, ray.map(|r| (r, c)), index, t_exit) {
                return Visit::Stop;
            }
        } else if !self.occupied(c >> self.log2_edge()) {
            return Visit::LeaveBlock;
        } else if search.done_at(t_exit) {
            return Visit::Stop;
        }
        Visit::Next
    }

    /// log2 of the macrocell edge A.
    #[inline]
    pub fn log2_edge(&self) -> u32 {
        self.a.trailing_zeros()
    }

    /// The fine grid's ray `fine_ray` in the macro grid's space (exact: A is a power of two).
    #[inline]
    pub fn macro_ray(&self, fine_ray: &GridRay) -> GridRay {
        let a = self.a as f32;
        GridRay { o: fine_ray.o / a, d: fine_ray.d / a, inv_d: fine_ray.inv_d * a, ..*fine_ray }
    }

    /// Macrocell `m`'s first fine cell, and `fine_ray` over `[t0, t1]` in the space of its block
    /// of A³ fine cells.
    #[inline]
    pub fn block_ray(&self, m: UVec3, fine_ray: &GridRay, t0: f32, t1: f32) -> (UVec3, GridRay) {
        let lo = m * self.a;
        (lo, GridRay { o: fine_ray.o - lo.as_vec3(), t0, t1, ..*fine_ray })
    }

    /// The fine cells of the macrocell whose first fine cell is `lo`: A on every axis, fewer
    /// in the last macrocell of an axis the grid's end cuts short.
    #[inline]
    pub fn block_res(&self, lo: UVec3) -> UVec3 {
        UVec3::splat(self.a).min(self.fine.geom.res - lo)
    }

    /// Walks the fine cells of macrocell `m` along `fine_ray` over `[t0, t1]` (no slab checks:
    /// they are Amanatides–Woo's, see `trace_flat`); true when the search is done.
    #[inline(never)]
    fn walk_block(
        &self,
        m: UVec3,
        fine_ray: &GridRay,
        (t0, t1): (f32, f32),
        traversal: Traversal,
        search: &mut ClosestHit,
    ) -> bool {
        let (lo, sub) = self.block_ray(m, fine_ray, t0, t1);
        let fine = &self.fine;
        let (done, cells) = walk_counted(traversal, &sub, self.block_res(lo), |c, _, t_exit| {
            fine.visit(search, None, fine.geom.cell_index(lo + c), t_exit)
        });
        search.visit_cells(cells);
        done
    }
}

/// Refuses a macrocell size that is not a power of two ≤ 64.
pub fn check_macro_size(a: u32) -> Result<(), BuildError> {
    if !a.is_power_of_two() || a > 64 {
        return Err(BuildError::InvalidParameter(format!("macrocell size {a} must be a power of two ≤ 64")));
    }
    Ok(())
}

/// The macro grid over a fine grid of `res`: macrocells of edge `a` from the origin, the last on
/// an axis cut short where `res` is not a multiple of `a`.
pub fn macro_resolution(res: UVec3, a: u32) -> UVec3 {
    UVec3::new(res.x.div_ceil(a), res.y.div_ceil(a), res.z.div_ceil(a))
}

/// The index of the sample that costs least (of a non-empty list, e.g. one per [`MACRO_SIZES`]).
pub fn best_macro_sample(samples: &[MacroSample]) -> usize {
    (0..samples.len()).min_by(|&x, &y| samples[x].cost.total_cmp(&samples[y].cost)).expect("samples")
}

impl MacroSample {
    /// The sample of macrocells of edge `a` from their occupancy bits.
    pub fn from_occupancy(a: u32, macro_res: UVec3, occupancy: &[u32]) -> MacroSample {
        let cells = macro_res.x as u64 * macro_res.y as u64 * macro_res.z as u64;
        let occupied: u64 = occupancy.iter().map(|w| w.count_ones() as u64).sum();
        let f = occupied as f64 / cells as f64;
        MacroSample { a, macro_cells: cells, occupied, cost: 1.0 / a as f64 + FINE_STEP_WEIGHT * f }
    }
}

/// Macro resolution and occupancy bits of a fine grid for macrocells of each edge in `sizes`, in
/// one pass over its occupied cells (found from its occupancy words: most cells are empty).
fn occupancies(fine: &FlatGrid, sizes: &[u32]) -> Vec<(UVec3, Vec<u32>)> {
    let res = fine.geom.res;
    let mut out: Vec<(UVec3, Vec<u32>)> = sizes
        .iter()
        .map(|&a| {
            debug_assert!(a.is_power_of_two(), "macrocell size {a}");
            let m = macro_resolution(res, a);
            (m, vec![0u32; (m.x as usize * m.y as usize * m.z as usize).div_ceil(32)])
        })
        .collect();
    let shifts: Vec<u32> = sizes.iter().map(|a| a.trailing_zeros()).collect();
    let rx = res.x as usize;
    // Row by row of fine cells (x fastest), so a cell's macrocell is its row's first plus
    // x >> log2 A: no division per occupied cell.
    for z in 0..res.z {
        for y in 0..res.y {
            let first: Vec<usize> =
                shifts.iter().zip(&out).map(|(&s, (m, _))| linear_index(UVec3::new(0, y >> s, z >> s), *m)).collect();
            let base = (z as usize * res.y as usize + y as usize) * rx;
            let (mut i, end) = (base, base + rx);
            while i < end {
                let (w, off) = (i / WORD_CELLS, i % WORD_CELLS);
                let len = (WORD_CELLS - off).min(end - i);
                let mut bits = (fine.occupied[w].bits >> off) as u64 & ((1u64 << len) - 1);
                while bits != 0 {
                    let x = i - base + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    for ((&s, &f), (_, occ)) in shifts.iter().zip(&first).zip(&mut out) {
                        let k = f + (x >> s);
                        occ[k / 32] |= 1 << (k % 32);
                    }
                }
                i += len;
            }
        }
    }
    out
}
