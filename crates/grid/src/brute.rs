//! Brute-force closest hit over every triangle: the reference every grid is tested against.
//! Same triangle test, same tie-break, so a correct grid reproduces its hits bit for bit.
//!
//! [`trace`] tests the triangles one by one. [`BruteForce`] gives the same hits faster, for the
//! exactness matrices and the benchmarks' checks: the corners are stored as nine arrays, so the
//! watertight test's f32 pre-filter ([`crate::triangle::certainly_outside`]) runs over eight triangles at once
//! (compiled for AVX2, AVX and the baseline, picked at run time), lane by lane the scalar rule on
//! the same values; the triangles it cannot reject take the scalar exact test ([`intersect_prefiltered`]).

use glam::Vec3;
use gridrt_scene::{Hit, Ray};

use crate::ray::PreparedRay;
use crate::stats::RayStats;
use crate::triangle::{LANES, Lanes, certainly_outside_tris8, intersect, intersect_prefiltered, keep_closer};

/// Closest hit of `ray` among `tris` (t, then index), with stats (every triangle is a test).
pub fn trace(tris: &[[Vec3; 3]], ray: &Ray) -> (Hit, RayStats) {
    let Some(r) = PreparedRay::new(ray) else {
        return (Hit::MISS, RayStats::default());
    };
    let mut best = Hit::MISS;
    for (i, tri) in tris.iter().enumerate() {
        keep_closer(&mut best, intersect(&r, tri), i as u32);
    }
    (best, RayStats { cells: 0, tests: tris.len() as u32 })
}

/// The triangles of a scene with their corners in nine arrays of eight-triangle chunks (corner
/// `v`, axis `a` at `corner[3 * v + a]`, the last chunk padded): [`trace`]'s hits at several
/// times its speed.
#[derive(Clone, Debug)]
pub struct BruteForce<'a> {
    tris: &'a [[Vec3; 3]],
    corner: [Vec<Lanes>; 9],
}

impl<'a> BruteForce<'a> {
    pub fn new(tris: &'a [[Vec3; 3]]) -> BruteForce<'a> {
        let corner = std::array::from_fn(|k| {
            tris.chunks(LANES).map(|c| std::array::from_fn(|l| c.get(l).map_or(0.0, |t| t[k / 3][k % 3]))).collect()
        });
        BruteForce { tris, corner }
    }

    /// The same hit and stats as [`trace`] over the same triangles.
    pub fn trace(&self, ray: &Ray) -> (Hit, RayStats) {
        let Some(r) = PreparedRay::new(ray) else {
            return (Hit::MISS, RayStats::default());
        };
        (trace_chunks(self, &r), RayStats { cells: 0, tests: self.tris.len() as u32 })
    }
}

/// [`BruteForce::trace`] for a prepared ray, compiled for AVX2 and AVX besides the baseline and
/// chosen at run time (`multiversion`); the lanes do the scalar operations in the same order in
/// every version (no FMA contraction), so they reject what [`intersect`]'s pre-filter rejects.
#[allow(unsafe_code)] // the dispatch `multiversion` generates: a version runs only where its features are detected
#[multiversion::multiversion(targets("x86_64+avx2+fma", "x86_64+avx"))]
fn trace_chunks(b: &BruteForce, r: &PreparedRay) -> Hit {
    let mut best = Hit::MISS;
    let n = b.tris.len();
    // The corners' coordinates at the ray's permutation: corner v's (x, y, z) are arrays
    // 3v..3v + 3.
    let at = |v: usize, a: usize| &b.corner[3 * v + a][..];
    let axes = [0, 1, 2].map(|v| [at(v, r.kx), at(v, r.ky), at(v, r.kz)]);
    let [[x0, y0, z0], [x1, y1, z1], [x2, y2, z2]] = axes;
    for (k, start) in (0..n).step_by(LANES).enumerate() {
        let (x0, y0, z0, x1, y1, z1, x2, y2, z2) = (x0[k], y0[k], z0[k], x1[k], y1[k], z1[k], x2[k], y2[k], z2[k]);
        let corners = [[x0, y0, z0], [x1, y1, z1], [x2, y2, z2]];
        let mut keep = !certainly_outside_tris8(&corners, r.org_k, [r.sx, r.sy]) & ((1 << LANES) - 1);
        // Padding lanes past the last triangle.
        if start + LANES > n {
            keep &= (1u32 << (n - start)) - 1;
        }
        while keep != 0 {
            let i = start + keep.trailing_zeros() as usize;
            keep &= keep - 1;
            keep_closer(&mut best, intersect_prefiltered(r, &b.tris[i]), i as u32);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chunked brute force equals the one-by-one one, bit for bit, on a scene with shared
    /// edges and vertices, a tail chunk and rays along and between the triangles.
    #[test]
    fn chunked_brute_force_equals_the_one_by_one_test() {
        let mut tris = Vec::new();
        for i in 0..13 {
            for j in 0..7 {
                let (x, y) = (i as f32 * 0.5, j as f32 * 0.5);
                let z = ((i * 7 + j) % 5) as f32 * 0.1;
                tris.push([Vec3::new(x, y, z), Vec3::new(x + 0.5, y, z), Vec3::new(x, y + 0.5, z + 0.2)]);
                tris.push([Vec3::new(x + 0.5, y, z), Vec3::new(x + 0.5, y + 0.5, z), Vec3::new(x, y + 0.5, z + 0.2)]);
            }
        }
        tris.push(tris[3]); // a duplicate: the tie-break picks the smaller index
        let b = BruteForce::new(&tris);
        let mut hits = 0;
        for k in 0..4000u32 {
            let f = |s: u32| (k.wrapping_mul(2654435761).rotate_left(s) >> 8) as f32 / (1 << 24) as f32;
            let o = Vec3::new(f(0) * 8.0 - 1.0, f(5) * 5.0 - 1.0, 3.0 - f(9) * 6.0);
            // Aimed at a corner, an edge midpoint or a random point of the sheet.
            let t = tris[k as usize % tris.len()];
            let target = match k % 3 {
                0 => t[0],
                1 => (t[0] + t[1]) * 0.5,
                _ => Vec3::new(f(13) * 6.5, f(17) * 3.5, f(21) * 0.6),
            };
            let ray = Ray::new(o, target - o, 0.0, f32::INFINITY);
            let (a, sa) = trace(&tris, &ray);
            let (c, sc) = b.trace(&ray);
            assert!(a.same_bits(&c), "ray {k}: {a:?} vs {c:?}");
            assert_eq!(sa, sc);
            hits += a.is_hit() as u32;
        }
        assert!(hits > 2000, "{hits} hits");
    }
}
