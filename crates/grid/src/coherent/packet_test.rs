//! One triangle against every active ray of a packet, eight rays at a time.
//!
//! The rays are grouped by the axis permutation of their watertight test (most packets have
//! one). For a group, the triangle's corners are read at the group's permutation and the f32
//! pre-filter of [`crate::triangle::certainly_outside`] runs for eight rays at once with the
//! `wide` crate (AVX when the build enables it, two SSE halves on baseline x86-64, NEON or
//! simd128 elsewhere, scalar otherwise), with the same operations in the same order, so it
//! rejects exactly the rays the scalar pre-filter rejects. The rays it cannot reject take the
//! scalar [`crate::triangle::intersect`], so hits are those of single rays, bit for bit.

use glam::Vec3;
use gridrt_scene::Hit;
use wide::f32x8;

use super::frustum::Lane;
use crate::ray::PreparedRay;
use crate::triangle::{closer, intersect};

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
        let mut changed = false;
        let p: &[f32; 9] = bytemuck::cast_ref(tri);
        for g in &self.groups {
            let [kx, ky, kz] = g.perm;
            let corner =
                |v: usize| (f32x8::splat(p[3 * v + kx]), f32x8::splat(p[3 * v + ky]), f32x8::splat(p[3 * v + kz]));
            let (a, b, c) = (corner(0), corner(1), corner(2));
            for chunk in (g.start..g.start + g.len).step_by(LANES) {
                let load = |v: &[f32]| f32x8::new(v[chunk..chunk + LANES].try_into().expect("eight lanes"));
                let (ox, oy, oz, sx, sy) =
                    (load(&self.ox), load(&self.oy), load(&self.oz), load(&self.sx), load(&self.sy));
                // crate::triangle::intersect's shear, eight rays at once.
                let sheared = |(x, y, z): (f32x8, f32x8, f32x8)| {
                    let z = z - oz;
                    ((x - ox) - sx * z, (y - oy) - sy * z)
                };
                let (ax, ay) = sheared(a);
                let (bx, by) = sheared(b);
                let (cx, cy) = sheared(c);
                let mut keep = !certainly_outside8([ax, ay], [bx, by], [cx, cy]).to_bitmask() & 0xff;
                while keep != 0 {
                    let k = chunk + keep.trailing_zeros() as usize;
                    keep &= keep - 1;
                    let i = self.lane[k];
                    if i == u32::MAX {
                        continue;
                    }
                    let i = i as usize;
                    if let Some(h) = intersect(&self.ray[k], tri)
                        && closer(h.t, id, best[i].t, best[i].triangle)
                    {
                        best[i] = Hit { t: h.t, triangle: id, u: h.u, v: h.v };
                        changed = true;
                    }
                }
            }
        }
        changed
    }
}

/// [`crate::triangle::certainly_outside`] for eight rays: all-ones lanes where the origin is
/// certainly outside.
#[inline]
fn certainly_outside8(a: [f32x8; 2], b: [f32x8; 2], c: [f32x8; 2]) -> f32x8 {
    let four_eps = f32x8::splat(crate::triangle::EDGE_ERROR_SCALE);
    let tiny = f32x8::splat(crate::triangle::EDGE_ERROR_FLOOR);
    let edge = |x: f32x8, y: f32x8, z: f32x8, w: f32x8| {
        let (p, q) = (x * y, z * w);
        (p - q, (p.abs() + q.abs()) * four_eps + tiny)
    };
    let (u, eu) = edge(c[0], b[1], c[1], b[0]);
    let (v, ev) = edge(a[0], c[1], a[1], c[0]);
    let (w, ew) = edge(b[0], a[1], b[1], a[0]);
    let negative = u.simd_lt(-eu) | v.simd_lt(-ev) | w.simd_lt(-ew);
    let positive = u.simd_gt(eu) | v.simd_gt(ev) | w.simd_gt(ew);
    negative & positive
}
