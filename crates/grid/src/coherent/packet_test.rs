//! One triangle against every active ray of a packet, eight rays at a time.
//!
//! The rays are grouped by the axis permutation of their watertight test (most packets have
//! one). For a group, the triangle's corners are read at the group's permutation and the f32
//! pre-filter of [`crate::triangle::certainly_outside`] runs for eight rays at once: eight-lane
//! arrays the compiler vectorizes, in versions for AVX2 (one 256-bit register), AVX and the
//! baseline (two SSE halves on x86-64; NEON or simd128 elsewhere), picked at run time by the
//! CPU's features (`multiversion`). Each lane does the scalar pre-filter's operations in the same
//! order, so it rejects exactly the rays the scalar pre-filter rejects. The rays it cannot reject take the
//! scalar [`crate::triangle::intersect_prefiltered`], so hits are those of single rays, bit for bit.

use glam::Vec3;
use gridrt_scene::Hit;

use super::frustum::Lane;
use crate::ray::PreparedRay;
use crate::triangle::{certainly_outside, intersect_prefiltered, keep_closer, shear};

/// Rays per SIMD chunk.
pub const LANES: usize = 8;

/// Rays sharing one axis permutation: `start..start + len` of the gathered arrays (padded to
/// whole chunks of eight).
#[derive(Clone, Copy, Debug)]
struct Group {
    perm: [usize; 3],
    start: usize,
    len: usize,
}

/// The active rays of a packet, gathered by permutation into arrays of eight-ray chunks.
#[derive(Clone, Debug, Default)]
pub struct PacketRays {
    groups: Vec<Group>,
    /// Where each lane's ray is (`u32::MAX`: not gathered or removed).
    pos: Vec<u32>,
    /// Rays removed since the last gather.
    dead: usize,
    /// Lane index of each ray (`u32::MAX` in padding and for removed rays).
    lane: Vec<u32>,
    ray: Vec<PreparedRay>,
    /// The origin at the permutation (x, y, z) and the shear.
    ox: Vec<f32>,
    oy: Vec<f32>,
    oz: Vec<f32>,
    sx: Vec<f32>,
    sy: Vec<f32>,
}

impl PacketRays {
    /// The rays of the `active` lanes (`lanes` many in the packet).
    pub fn gather(&mut self, lanes: &[Lane], active: &[u32]) {
        self.groups.clear();
        self.lane.clear();
        self.ray.clear();
        for v in [&mut self.ox, &mut self.oy, &mut self.oz, &mut self.sx, &mut self.sy] {
            v.clear();
        }
        self.pos.clear();
        self.pos.resize(lanes.len(), u32::MAX);
        self.dead = 0;
        // The permutation is fixed by the dominant axis kz and whether kx, ky are swapped.
        let code = |r: &PreparedRay| r.kz * 2 + (r.kx != (r.kz + 1) % 3) as usize;
        let mut present = [false; 6];
        for &i in active {
            present[code(lanes[i as usize].ray.as_ref().expect("active lanes are valid"))] = true;
        }
        for (c, _) in present.iter().enumerate().filter(|(_, p)| **p) {
            let start = self.lane.len();
            let mut perm = [0; 3];
            for &i in active {
                let r = lanes[i as usize].ray.expect("active lanes are valid");
                if code(&r) == c {
                    perm = [r.kx, r.ky, r.kz];
                    self.pos[i as usize] = self.lane.len() as u32;
                    self.push(i, r);
                }
            }
            let len = self.lane.len() - start;
            let filler = self.ray[start];
            while !(self.lane.len() - start).is_multiple_of(LANES) {
                self.push(u32::MAX, filler);
            }
            self.groups.push(Group { perm, start, len });
        }
    }

    /// Drops the ray of lane `i` (it is skipped from now on); returns the rays dropped since
    /// the last gather.
    #[inline]
    pub fn remove(&mut self, i: u32) -> usize {
        let k = self.pos[i as usize];
        if k != u32::MAX {
            self.lane[k as usize] = u32::MAX;
            self.pos[i as usize] = u32::MAX;
            self.dead += 1;
        }
        self.dead
    }

    fn push(&mut self, lane: u32, r: PreparedRay) {
        self.lane.push(lane);
        self.ray.push(r);
        self.ox.push(r.org_k[0]);
        self.oy.push(r.org_k[1]);
        self.oz.push(r.org_k[2]);
        self.sx.push(r.sx);
        self.sy.push(r.sy);
    }

    /// Tests triangle `tri` (index `id`) against every gathered ray, keeping each lane's
    /// closest hit in `best`; true when some lane's hit changed.
    #[inline]
    pub fn test(&self, tri: &[Vec3; 3], id: u32, best: &mut [Hit]) -> bool {
        test_rays(self, tri, id, best)
    }
}

/// [`PacketRays::test`], compiled for AVX2 and AVX besides the baseline and chosen at run time
/// by the CPU's features (`multiversion`). The pre-filter's eight lanes are plain arrays the
/// compiler vectorizes for each version: one AVX register, or two SSE halves. The operations and
/// their order are the same in every version (no FMA contraction), so every version rejects the
/// same rays.
#[allow(unsafe_code)] // the dispatch `multiversion` generates: a version runs only where its features are detected
#[multiversion::multiversion(targets("x86_64+avx2+fma", "x86_64+avx"))]
fn test_rays(rays: &PacketRays, tri: &[Vec3; 3], id: u32, best: &mut [Hit]) -> bool {
    let mut changed = false;
    let p: &[f32; 9] = bytemuck::cast_ref(tri);
    for g in &rays.groups {
        let [kx, ky, kz] = g.perm;
        let corners = [0, 1, 2].map(|v| [p[3 * v + kx], p[3 * v + ky], p[3 * v + kz]]);
        for chunk in (g.start..g.start + g.len).step_by(LANES) {
            let lanes = |v: &[f32]| -> Lanes { v[chunk..chunk + LANES].try_into().expect("eight lanes") };
            let o = [lanes(&rays.ox), lanes(&rays.oy), lanes(&rays.oz)];
            let shear = [lanes(&rays.sx), lanes(&rays.sy)];
            let mut keep = !certainly_outside8(&corners, &o, &shear) & 0xff;
            while keep != 0 {
                let k = chunk + keep.trailing_zeros() as usize;
                keep &= keep - 1;
                let i = rays.lane[k];
                if i == u32::MAX {
                    continue;
                }
                let i = i as usize;
                changed |= keep_closer(&mut best[i], intersect_prefiltered(&rays.ray[k], tri), id);
            }
        }
    }
    changed
}

/// Eight rays' values of one quantity.
type Lanes = [f32; LANES];

/// [`crate::triangle::intersect`]'s shear and [`crate::triangle::certainly_outside`] for eight
/// rays (origins `o`, shear `s`) against one triangle's corners at their permutation: a bit per
/// ray whose origin is certainly outside. Each lane calls the scalar rule; the loop vectorizes.
#[inline(always)]
fn certainly_outside8(corners: &[[f32; 3]; 3], o: &[Lanes; 3], s: &[Lanes; 2]) -> u32 {
    let mut mask = 0u32;
    for l in 0..LANES {
        let sheared = |c: &[f32; 3]| {
            let [x, y, _] = shear(*c, [o[0][l], o[1][l], o[2][l]], [s[0][l], s[1][l]]);
            [x, y]
        };
        let outside = certainly_outside(sheared(&corners[0]), sheared(&corners[1]), sheared(&corners[2]));
        mask |= u32::from(outside) << l;
    }
    mask
}
