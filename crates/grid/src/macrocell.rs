//! Macrocells (Parker et al. 1999): a coarse occupancy grid over A×A×A blocks of a flat grid.
//!
//! The ray walks the macro grid first; an empty macrocell is crossed in one step, and only
//! inside an occupied one does it walk the fine cells of that block. The fine grid's resolution
//! is rounded up to a multiple of A on every axis, so macrocell boundaries are exactly fine-cell
//! boundaries; A is a power of two, so the macro grid-space ray is the fine one scaled by 1/A
//! without rounding.
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
//! stepping cost is ≈ (m/A + f_A·m)·Tstep (the intersection term does not depend on A). f_A is
//! counted exactly for A ∈ {2, 4, 8, 16}; the A minimising 1/A + f_A wins.

use glam::{UVec3, Vec3};
use gridrt_scene::{Aabb, Hit, Ray};
use serde::{Deserialize, Serialize};

use crate::BuildError;
use crate::build::{BuildOptions, PhaseTimes};
use crate::flat::FlatGrid;
use crate::geometry::{GridGeometry, GridRay, linear_index};
use crate::stats::RayStats;
use crate::trace::TraceOptions;
use crate::trace::closest_hit::{ClosestHit, closest_hit};
use crate::traversal::amanatides_woo::AmanatidesWoo;
use crate::traversal::{Traversal, Visit, walk_counted};

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
    /// 1/A + f_A: the relative stepping cost the choice minimises.
    pub cost: f64,
}

impl MacrocellGrid {
    /// Builds the fine grid at `res` (rounded up to multiples of A) and the macro occupancy.
    /// `a = None` lets the cost model choose A (see the module doc). `bounds`: of `tris`.
    pub fn build(
        tris: &[[Vec3; 3]],
        bounds: &Aabb,
        res: [u32; 3],
        a: Option<u32>,
        opts: BuildOptions,
        times: &mut PhaseTimes,
    ) -> Result<(MacrocellGrid, Vec<MacroSample>), BuildError> {
        let build_fine =
            |res: [u32; 3], times: &mut PhaseTimes| FlatGrid::build(tris, GridGeometry::new(bounds, res), opts, times);
        let (a, samples, probe) = match a {
            Some(a) => {
                check_macro_size(a)?;
                (a, Vec::new(), None)
            }
            None => {
                // Occupancy of each candidate A, from a fine grid at a resolution divisible by 16
                // (and so by every candidate).
                let fine = build_fine(fine_resolution(res, PROBE_MULTIPLE), times)?;
                let samples: Vec<MacroSample> =
                    times.record("macro-size", || MACRO_SIZES.iter().map(|&a| sample(&fine, a)).collect());
                (best_macro_size(&samples), samples, Some(fine))
            }
        };
        // The probe is the final fine grid when rounding to A gives the same resolution.
        let target = fine_resolution(res, a);
        let fine = match probe {
            Some(f) if f.geom.res.to_array() == target => f,
            _ => build_fine(target, times)?,
        };
        let grid = times.record("occupancy", || {
            let (macro_res, occupancy) = occupancy(&fine, a);
            MacrocellGrid { fine, a, macro_res, occupancy }
        });
        Ok((grid, samples))
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

    /// Closest hit. Amanatides–Woo: one walk of the fine cells that leaves an empty macrocell
    /// in one jump ([`AmanatidesWoo::walk_blocks`]); the other walkers: the macro walk, and a
    /// walk of the fine cells inside each occupied macrocell.
    pub fn trace(&self, tris: &[[Vec3; 3]], ray: &Ray, opts: TraceOptions) -> (Hit, RayStats) {
        let traversal = opts.traversal;
        if traversal == Traversal::AmanatidesWoo {
            let r = closest_hit(tris, ray, opts, |search| {
                let Some(fine_ray) = self.fine.geom.clip(&search.ray) else { return };
                let walk = AmanatidesWoo::new(&fine_ray, self.fine.geom.res);
                let empty = |m: UVec3| !self.occupied(m);
                let (_, cells) =
                    walk.walk_blocks(self.log2_edge(), empty, |c, index, t_exit| self.visit(search, c, index, t_exit));
                search.visit_cells(cells);
            });
            return r;
        }
        closest_hit(tris, ray, opts, |search| {
            let Some(fine_ray) = self.fine.geom.clip(&search.ray) else { return };
            let macro_ray = self.macro_ray(&fine_ray);
            let mut t_enter = fine_ray.t0;
            let (_, cells) = walk_counted(traversal, &macro_ray, self.macro_res, |m, maddr, m_exit| {
                // An occupied macrocell's fine walk is a call, keeping the macro walk's loop
                // small (most macrocells are empty).
                let entered = std::mem::replace(&mut t_enter, m_exit);
                if self.occupied_at(maddr) && self.walk_block(m, &fine_ray, entered, m_exit, traversal, search) {
                    return true;
                }
                search.done_at(m_exit)
            });
            search.visit_cells(cells);
        })
    }

    /// A fine cell's visit in the walk over macrocells: its tests when it holds triangles, a
    /// jump out of its macrocell when that is empty.
    #[inline]
    pub fn visit(&self, search: &mut ClosestHit, c: UVec3, index: usize, t_exit: f32) -> Visit {
        if self.fine.is_occupied(index) {
            if self.fine.test_occupied(search, index, t_exit) {
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

    /// Walks the fine cells of macrocell `m` along `fine_ray` over `[t0, t1]`; true when the
    /// search is done.
    #[inline(never)]
    fn walk_block(
        &self,
        m: UVec3,
        fine_ray: &GridRay,
        t0: f32,
        t1: f32,
        traversal: Traversal,
        search: &mut ClosestHit,
    ) -> bool {
        let (lo, sub) = self.block_ray(m, fine_ray, t0, t1);
        let fine = &self.fine;
        let (done, cells) = walk_counted(traversal, &sub, UVec3::splat(self.a), |c, _, t_exit| {
            fine.visit(search, fine.geom.cell_index(lo + c), t_exit)
        });
        search.visit_cells(cells);
        done
    }
}

/// The probe grid's resolution is a multiple of this (and so of every candidate A).
pub const PROBE_MULTIPLE: u32 = 16;

/// Refuses a macrocell size that is not a power of two ≤ 64.
pub fn check_macro_size(a: u32) -> Result<(), BuildError> {
    if !a.is_power_of_two() || a > 64 {
        return Err(BuildError::InvalidParameter(format!("macrocell size {a} must be a power of two ≤ 64")));
    }
    Ok(())
}

/// The fine resolution for macrocells of edge `a`: `res` rounded up to multiples of `a`.
pub fn fine_resolution(res: [u32; 3], a: u32) -> [u32; 3] {
    res.map(|r| r.max(1).div_ceil(a) * a)
}

/// The macro grid over a fine grid of `res` (a multiple of `a`).
pub fn macro_resolution(res: UVec3, a: u32) -> UVec3 {
    UVec3::new(res.x.div_ceil(a), res.y.div_ceil(a), res.z.div_ceil(a))
}

/// The A whose sample costs least.
pub fn best_macro_size(samples: &[MacroSample]) -> u32 {
    samples.iter().min_by(|x, y| x.cost.total_cmp(&y.cost)).map_or(MACRO_SIZES[0], |s| s.a)
}

impl MacroSample {
    /// The sample of macrocells of edge `a` from their occupancy bits.
    pub fn from_occupancy(a: u32, macro_res: UVec3, occupancy: &[u32]) -> MacroSample {
        let cells = macro_res.x as u64 * macro_res.y as u64 * macro_res.z as u64;
        let occupied: u64 = occupancy.iter().map(|w| w.count_ones() as u64).sum();
        MacroSample { a, macro_cells: cells, occupied, cost: 1.0 / a as f64 + occupied as f64 / cells as f64 }
    }
}

fn sample(fine: &FlatGrid, a: u32) -> MacroSample {
    let (macro_res, occ) = occupancy(fine, a);
    MacroSample::from_occupancy(a, macro_res, &occ)
}

/// Macro resolution and occupancy bits of a fine grid whose resolution is a multiple of `a`.
fn occupancy(fine: &FlatGrid, a: u32) -> (UVec3, Vec<u32>) {
    let res = fine.geom.res;
    let macro_res = macro_resolution(res, a);
    let n = macro_res.x as usize * macro_res.y as usize * macro_res.z as usize;
    let mut occupancy = vec![0u32; n.div_ceil(32)];
    for z in 0..res.z {
        for y in 0..res.y {
            for x in 0..res.x {
                let c = UVec3::new(x, y, z);
                let i = fine.geom.cell_index(c);
                if fine.is_occupied(i) {
                    let m = c / a;
                    let k = linear_index(m, macro_res);
                    occupancy[k / 32] |= 1 << (k % 32);
                }
            }
        }
    }
    (macro_res, occupancy)
}
