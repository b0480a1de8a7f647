//! Watertight ray/triangle intersection (Woop, Benthin, Wald 2013), the one test every
//! traversal and the brute-force reference share, so their hits agree to the bit.
//!
//! The ray is prepared once ([`PreparedRay`]): the dominant direction axis becomes z, and a
//! shear maps the direction onto +z. Each triangle is translated to the ray origin and sheared
//! the same way; the 2-D edge functions U, V, W then decide inside/outside. A shared edge is
//! evaluated from the same sheared vertices in both triangles (only the operand order flips,
//! which negates the result exactly), so no ray slips between two triangles.
//!
//! Differences from the paper, on purpose:
//! - the edge functions U, V, W are always evaluated with an exact sign: the sheared f32
//!   coordinates are multiplied in f64 (exact: 24 + 24 mantissa bits fit in 53) and the
//!   difference rounded once. The paper does this only when a float result is exactly zero;
//!   that is not enough: for a triangle seen nearly edge-on from far away, both products of an
//!   edge function round to the same float, U = V = 0 and the "hit" lands hundreds of units
//!   from the triangle (found on Crytek Sponza). With exact signs, "inside" is decided exactly
//!   for the rounded 2-D points, so a hit is always within rounding distance of the triangle,
//!   and a shared edge still gets exactly opposite signs in its two triangles (watertight).
//!   `det`, `t`, `u`, `v` follow in f64 and are rounded to f32 once. (WGSL has no f64; the GPU
//!   port gets the same signs from Kahan's FMA difference of products.)
//!   An f32 pre-filter ([`certainly_outside`]) rejects first the misses whose signs the f32
//!   edge functions already decide within a proven error bound, so it changes no result.
//! - an edge function of exactly zero counts as inside, so a ray through an edge or vertex hits
//!   every triangle around it (the deterministic tie-break then picks the smallest index).
//! - no back-face culling; `t` must be finite and inside `[tmin, tmax]` (closed interval).

use glam::Vec3;
use gridrt_scene::Hit;

use crate::ray::PreparedRay;

/// A hit before it becomes a [`gridrt_scene::Hit`]: parameter and barycentrics of corners 1, 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// A corner `c` (at the ray's axis permutation) in the watertight test's ray space: translated
/// by the origin `o` (same permutation) and sheared by `s` (x, y; z is not yet scaled). The one
/// place these operations are written: the batched pre-filters (packets, brute force) call it
/// too, so their values are bit for bit those of [`intersect`].
#[inline(always)]
pub fn shear(c: [f32; 3], o: [f32; 3], s: [f32; 2]) -> [f32; 3] {
    let z = c[2] - o[2];
    [(c[0] - o[0]) - s[0] * z, (c[1] - o[1]) - s[1] * z, z]
}

/// The corners of `tri` read at an axis permutation `[kx, ky, kz]`: nine floats (an index chosen
/// at run time into a `Vec3` would go through the stack), the values [`shear`] takes.
#[inline(always)]
pub fn permuted_corners(tri: &[Vec3; 3], [kx, ky, kz]: [usize; 3]) -> [[f32; 3]; 3] {
    let p: &[f32; 9] = bytemuck::cast_ref(tri);
    [0, 1, 2].map(|v| [p[3 * v + kx], p[3 * v + ky], p[3 * v + kz]])
}

/// Watertight intersection of `r` with triangle `tri`; `None` on a miss.
#[inline]
pub fn intersect(r: &PreparedRay, tri: &[Vec3; 3]) -> Option<TriHit> {
    intersect_with::<true>(r, tri)
}

/// [`intersect`] for a triangle the batched pre-filter ([`certainly_outside_tris8`] and its
/// packet twin) has already kept: the same result without running the pre-filter again.
#[inline]
pub fn intersect_prefiltered(r: &PreparedRay, tri: &[Vec3; 3]) -> Option<TriHit> {
    intersect_with::<false>(r, tri)
}

/// The watertight test, with or without the f32 pre-filter (which changes no result).
#[inline(always)]
fn intersect_with<const PREFILTER: bool>(r: &PreparedRay, tri: &[Vec3; 3]) -> Option<TriHit> {
    // The corners as nine floats, read at the ray's axis permutation (an index chosen at run
    // time into a `Vec3` would go through the stack); the same operations as translating the
    // whole corner and picking its components.
    // [`permuted_corners`]' reads, one corner at a time: building the nine floats first made
    // this test 20% slower on the Cornell box's camera rays (one thread).
    let p: &[f32; 9] = bytemuck::cast_ref(tri);
    let (kx, ky, kz) = (r.kx, r.ky, r.kz);
    let [ox, oy, oz] = r.org_k;
    let sheared = |v: usize| shear([p[3 * v + kx], p[3 * v + ky], p[3 * v + kz]], [ox, oy, oz], [r.sx, r.sy]);
    let [ax, ay, az] = sheared(0);
    let [bx, by, bz] = sheared(1);
    let [cx, cy, cz] = sheared(2);
    // Most triangles a ray is tested against are misses the f32 edge functions already
    // decide; the exact f64 signs are needed only for the rest.
    if PREFILTER && certainly_outside([ax, ay], [bx, by], [cx, cy]) {
        return None;
    }
    let (hit, is_hit) = exact_hit([ax, ay, az], [bx, by, bz], [cx, cy, cz], r.sz, r.tmin, r.tmax);
    is_hit.then_some(hit)
}

/// The exact test on a ray's sheared corners `a`, `b`, `c` (z not yet scaled by `sz`), the one
/// place its arithmetic is written: the f64 edge functions (exact signs), `det`, `t`, `u`, `v`
/// rounded once, and whether that is a hit in `[tmin, tmax]`. No branches (every quantity is
/// computed, a miss's too), so eight lanes of it vectorize ([`intersect8_prefiltered`]).
#[inline(always)]
fn exact_hit(a: [f32; 3], b: [f32; 3], c: [f32; 3], sz: f32, tmin: f32, tmax: f32) -> (TriHit, bool) {
    let (ax, ay, bx, by, cx, cy) = (a[0] as f64, a[1] as f64, b[0] as f64, b[1] as f64, c[0] as f64, c[1] as f64);
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    // Inside (or on an edge) when the signs do not disagree.
    let inside = !((u < 0.0) | (v < 0.0) | (w < 0.0)) | !((u > 0.0) | (v > 0.0) | (w > 0.0));
    let det = u + v + w;
    let (az, bz, cz) = ((sz * a[2]) as f64, (sz * b[2]) as f64, (sz * c[2]) as f64);
    let t = ((u * az + v * bz + w * cz) / det) as f32;
    // det = 0 (the ray in the triangle's plane) is no hit. A t that overflows f32 (either sign:
    // a ray with tmin = -inf and a tiny direction meets a triangle behind it "at -inf") is none.
    let hit = inside & (det != 0.0) & (t >= tmin) & (t <= tmax) & t.is_finite();
    (TriHit { t, u: (v / det) as f32, v: (w / det) as f32 }, hit)
}

/// The bound on an f32 edge function's rounding error is `(|p| + |q|)·EDGE_ERROR_SCALE +
/// EDGE_ERROR_FLOOR` (see [`certainly_outside`]); the packet pre-filter uses the same bound.
pub const EDGE_ERROR_SCALE: f32 = 1.0 / (1u32 << 22) as f32;
pub const EDGE_ERROR_FLOOR: f32 = f32::MIN_POSITIVE;

/// Whether the sheared 2-D corners `a`, `b`, `c` certainly leave the origin outside: the edge
/// functions in f32, each with a bound on its rounding error, show two of them with certain,
/// opposite signs. Never true when the exact test would find the origin inside (the f64 signs
/// of [`intersect`] are the exact signs), so skipping the exact test then changes no result.
///
/// Error bound: with unit roundoff ε = 2⁻²⁴, p = fl(x·y) and q = fl(z·w) are each within
/// ε·|p|(1 + ε) of the exact products, and fl(p − q) within ε·|p − q| of p − q, so the f32 edge
/// function is within 2ε(1 + ε)(|p| + |q|) of the exact one, plus 2⁻¹⁴⁹ per product when
/// they are subnormal. The bound used, fl(|p| + |q|)·2⁻²² + 2⁻¹²⁶, is larger than both. An
/// overflow makes the bound infinite or a value NaN, and every comparison with them false.
#[inline]
pub fn certainly_outside(a: [f32; 2], b: [f32; 2], c: [f32; 2]) -> bool {
    let edge = |x: f32, y: f32, z: f32, w: f32| {
        let (p, q) = (x * y, z * w);
        (p - q, (p.abs() + q.abs()) * EDGE_ERROR_SCALE + EDGE_ERROR_FLOOR)
    };
    let (u, eu) = edge(c[0], b[1], c[1], b[0]);
    let (v, ev) = edge(a[0], c[1], a[1], c[0]);
    let (w, ew) = edge(b[0], a[1], b[1], a[0]);
    let negative = (u < -eu) | (v < -ev) | (w < -ew);
    let positive = (u > eu) | (v > ev) | (w > ew);
    negative & positive
}

/// Triangles (or rays) per pre-filter chunk of the batched tests.
pub const LANES: usize = 8;

/// One coordinate of eight triangles' corners (or of eight rays).
pub type Lanes = [f32; LANES];

/// [`certainly_outside`] for eight triangles against one ray: `c[v][a]` holds corner `v`'s
/// coordinate `a` at the ray's permutation (kx, ky, kz) for each lane, `o` the origin at that
/// permutation and `s` the shear. A bit per lane whose triangle certainly misses. Each lane does
/// the scalar rule's operations in the same order, so it rejects exactly what
/// [`intersect`]'s pre-filter rejects; the loop vectorizes in the caller's target features.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // `l` is the lane of every one of the nine arrays
pub fn certainly_outside_tris8(c: &[[Lanes; 3]; 3], o: [f32; 3], s: [f32; 2]) -> u32 {
    let mut mask = 0u32;
    for l in 0..LANES {
        let sheared = |v: usize| {
            let [x, y, _] = shear([c[v][0][l], c[v][1][l], c[v][2][l]], o, s);
            [x, y]
        };
        mask |= u32::from(certainly_outside(sheared(0), sheared(1), sheared(2))) << l;
    }
    mask
}

/// The triangles `ids` of `tris` (at most [`LANES`]) a ray may hit: a bit per entry of `ids`
/// that [`certainly_outside`] cannot reject (the others certainly miss). The corners are read
/// at the ray's permutation into eight lanes and pre-filtered together; compiled for AVX2 and
/// AVX besides the baseline and chosen at run time (`multiversion`), every version doing the
/// same operations in the same order (no FMA contraction).
#[allow(unsafe_code)] // the dispatch `multiversion` generates: a version runs only where its features are detected
#[multiversion::multiversion(targets("x86_64+avx2+fma", "x86_64+avx"))]
pub fn may_hit8(r: &PreparedRay, tris: &[[Vec3; 3]], ids: &[u32]) -> u32 {
    let n = ids.len().min(LANES);
    let mut c = [[[0.0f32; LANES]; 3]; 3];
    let perm = [r.kx, r.ky, r.kz];
    for (l, &id) in ids[..n].iter().enumerate() {
        let p: &[f32; 9] = bytemuck::cast_ref(&tris[id as usize]);
        for v in 0..3 {
            for a in 0..3 {
                c[v][a][l] = p[3 * v + perm[a]];
            }
        }
    }
    !certainly_outside_tris8(&c, r.org_k, [r.sx, r.sy]) & ((1u32 << n) - 1)
}

/// Eight rays of one axis permutation in lanes, as the watertight test reads them: origin at
/// the permutation, shear, and interval ([`PreparedRay`]'s `org_k`, `sx`, `sy`, `sz`, `tmin`,
/// `tmax`).
#[derive(Clone, Copy, Debug)]
pub struct RayLanes {
    pub o: [Lanes; 3],
    pub s: [Lanes; 3],
    pub tmin: Lanes,
    pub tmax: Lanes,
}

/// [`intersect_prefiltered`] of one triangle against eight rays that share an axis
/// permutation (`c`: the triangle's corners at that permutation): a hit per lane, and a bit per
/// lane that hits. Each lane runs the scalar test's [`exact_hit`], so its hit is the scalar
/// test's bit for bit (a unit test compares them); the lanes are plain arrays the caller's
/// target features vectorize (f64 in two halves of four). A packet tests a chunk's rays so when the
/// pre-filter keeps several of them.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // `l` is the lane of every array
pub fn intersect8_prefiltered(c: &[[f32; 3]; 3], r: &RayLanes) -> ([TriHit; LANES], u32) {
    let mut hits = [TriHit { t: 0.0, u: 0.0, v: 0.0 }; LANES];
    let mut mask = 0u32;
    for l in 0..LANES {
        let sheared = |v: usize| shear(c[v], [r.o[0][l], r.o[1][l], r.o[2][l]], [r.s[0][l], r.s[1][l]]);
        let (hit, is_hit) = exact_hit(sheared(0), sheared(1), sheared(2), r.s[2][l], r.tmin[l], r.tmax[l]);
        hits[l] = hit;
        mask |= u32::from(is_hit) << l;
    }
    (hits, mask)
}

/// Keeps `hit` of triangle `tri` as `best` when it is [`closer`]; true when it was. The one
/// place a candidate replaces the best hit, for every search (single rays, packets, brute
/// force).
#[inline(always)]
pub fn keep_closer(best: &mut Hit, hit: Option<TriHit>, tri: u32) -> bool {
    match hit {
        Some(h) if closer(h.t, tri, best.t, best.triangle) => {
            *best = Hit { t: h.t, triangle: tri, u: h.u, v: h.v };
            true
        }
        _ => false,
    }
}

/// Deterministic order of candidate hits: smaller `t`, then smaller triangle index.
#[inline]
pub fn closer(t: f32, tri: u32, best_t: f32, best_tri: u32) -> bool {
    t < best_t || (t == best_t && tri < best_tri)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gridrt_scene::Ray;

    /// The eight-lane exact test gives each lane the scalar test's result bit for bit: rays of
    /// every permutation aimed at corners, edge midpoints, inside and outside points of
    /// triangles of every size (degenerate ones too), with intervals that cut the hit off.
    #[test]
    fn intersect8_is_the_scalar_test_lane_by_lane() {
        let f = |k: u32, s: u32| (k.wrapping_mul(2654435761).rotate_left(s) >> 8) as f32 / (1 << 24) as f32;
        let (mut hits, mut misses) = (0, 0);
        for k in 0..4000u32 {
            let c = Vec3::new(f(k, 1), f(k, 7), f(k, 13)) * 4.0;
            let e = |s| {
                Vec3::new(f(k, s) - 0.5, f(k, s + 3) - 0.5, f(k, s + 5) - 0.5) * [0.0, 0.01, 1.0, 3.0][(k % 4) as usize]
            };
            // Every fifth triangle degenerate (a corner repeated).
            let tri = if k % 5 == 0 { [c, c + e(17), c + e(17)] } else { [c, c + e(17), c + e(23)] };
            let o = Vec3::new(f(k, 2) * 6.0 - 1.0, f(k, 9) * 6.0 - 1.0, f(k, 15) * 6.0 - 1.0);
            // One direction for the permutation, eight rays around it.
            let aim = [tri[0], (tri[1] + tri[2]) * 0.5, (tri[0] + tri[1] + tri[2]) / 3.0][(k % 3) as usize];
            let mut rays = Vec::new();
            let mut l = 0;
            while rays.len() < LANES && l < 64 {
                let jitter =
                    Vec3::new(f(k + l, 19) - 0.5, f(k + l, 25) - 0.5, f(k + l, 29) - 0.5) * 0.2 * (l % 3) as f32;
                let (t0, t1) = [(0.0, f32::INFINITY), (0.5, 0.9), (-1.0, 1.0), (0.0, 0.1)][(l % 4) as usize];
                if let Some(r) = PreparedRay::new(&Ray::new(o, aim + jitter - o, t0, t1))
                    && rays.first().is_none_or(|f: &PreparedRay| (f.kx, f.ky, f.kz) == (r.kx, r.ky, r.kz))
                {
                    rays.push(r);
                }
                l += 1;
            }
            if rays.len() < LANES {
                continue;
            }
            let lanes = |g: &dyn Fn(&PreparedRay) -> f32| -> Lanes { std::array::from_fn(|i| g(&rays[i])) };
            let r = RayLanes {
                o: [lanes(&|r| r.org_k[0]), lanes(&|r| r.org_k[1]), lanes(&|r| r.org_k[2])],
                s: [lanes(&|r| r.sx), lanes(&|r| r.sy), lanes(&|r| r.sz)],
                tmin: lanes(&|r| r.tmin),
                tmax: lanes(&|r| r.tmax),
            };
            let c = permuted_corners(&tri, [rays[0].kx, rays[0].ky, rays[0].kz]);
            let (lane_hits, mask) = intersect8_prefiltered(&c, &r);
            for (l, ray) in rays.iter().enumerate() {
                let scalar = intersect_prefiltered(ray, &tri);
                let bits = |h: TriHit| [h.t.to_bits(), h.u.to_bits(), h.v.to_bits()];
                assert_eq!(mask >> l & 1 == 1, scalar.is_some(), "triangle {k}, lane {l}");
                if let Some(h) = scalar {
                    assert_eq!(bits(lane_hits[l]), bits(h), "triangle {k}, lane {l}");
                    hits += 1;
                } else {
                    misses += 1;
                }
            }
        }
        assert!(hits > 3000 && misses > 3000, "{hits} hits, {misses} misses");
    }

    /// The eight-lane pre-filter keeps exactly the triangles the scalar pre-filter keeps, for
    /// every batch length and ray permutation, and never one `intersect` would hit and it drops.
    #[test]
    fn may_hit8_is_the_scalar_pre_filter_lane_by_lane_and_the_exact_test_follows_it() {
        let f = |k: u32, s: u32| (k.wrapping_mul(2654435761).rotate_left(s) >> 8) as f32 / (1 << 24) as f32;
        let tris: Vec<[Vec3; 3]> = (0..64u32)
            .map(|i| {
                let c = Vec3::new(f(i, 1), f(i, 7), f(i, 13)) * 4.0;
                let e = |s| Vec3::new(f(i, s) - 0.5, f(i, s + 3) - 0.5, f(i, s + 5) - 0.5);
                [c, c + e(17), c + e(23)]
            })
            .collect();
        let (mut kept, mut hits) = (0, 0);
        for k in 0..3000u32 {
            let o = Vec3::new(f(k, 2) * 6.0 - 1.0, f(k, 9) * 6.0 - 1.0, f(k, 15) * 6.0 - 1.0);
            // Aimed at a corner, an edge midpoint or anywhere (every permutation and sign).
            let t = tris[k as usize % tris.len()];
            let target = match k % 3 {
                0 => t[0],
                1 => (t[1] + t[2]) * 0.5,
                _ => Vec3::new(f(k, 19), f(k, 25), f(k, 29)) * 4.0,
            };
            let Some(r) = PreparedRay::new(&Ray::new(o, target - o, 0.0, f32::INFINITY)) else { continue };
            let n = 1 + k as usize % LANES;
            // A batch holding the triangle aimed at.
            let start = (k as usize % tris.len()).min(tris.len() - n);
            let ids: Vec<u32> = (start as u32..(start + n) as u32).collect();
            let mask = may_hit8(&r, &tris, &ids);
            for (l, &id) in ids.iter().enumerate() {
                let tri = &tris[id as usize];
                let p: &[f32; 9] = bytemuck::cast_ref(tri);
                let c = |v: usize| {
                    let [x, y, _] = shear([p[3 * v + r.kx], p[3 * v + r.ky], p[3 * v + r.kz]], r.org_k, [r.sx, r.sy]);
                    [x, y]
                };
                let keep = !certainly_outside(c(0), c(1), c(2));
                assert_eq!(mask >> l & 1 == 1, keep, "ray {k}, lane {l}");
                kept += keep as u32;
                if keep {
                    // Past the pre-filter, the exact test alone gives the same result.
                    assert_eq!(intersect_prefiltered(&r, tri), intersect(&r, tri), "ray {k}, lane {l}");
                }
                if intersect(&r, tri).is_some() {
                    assert!(keep, "ray {k}: a hit was pre-filtered out");
                    hits += 1;
                }
            }
            assert_eq!(mask >> n, 0, "ray {k}: padding lanes kept");
        }
        assert!(hits > 500 && kept > hits, "{hits} hits, {kept} kept");
    }
}
