//! A ray prepared once for the watertight triangle test (shaders/shared/ray.wgsl's
//! `PreparedRay`): the dominant direction axis, the shear, and the checks that refuse rays no
//! triangle can be hit by. Every structure and the brute-force reference start from it.
//!
//! A structure walks its cells along the ray in units of `t` ("walk units"), which are the
//! ray's own unless its direction is large: a direction beyond 2^16 (per component) could
//! overflow f32 in grid space (1e30 over cells of 1e-21, a scene 1e-18 across, is 1e51 cells per
//! unit of `t`), so the walk takes it scaled down by a power of two, `t_scale`, and its `t`
//! scaled up alike (both exact). The triangle test keeps the ray as given, so hits stay bit for
//! bit brute force's; the walk's stop test compares them in the ray's units
//! ([`PreparedRay::ray_t`]).

use glam::Vec3;
use gridrt_scene::Ray;

/// A ray with the per-ray constants of the watertight test.
#[derive(Clone, Copy, Debug)]
pub struct PreparedRay {
    pub org: Vec3,
    pub dir: Vec3,
    pub tmin: f32,
    pub tmax: f32,
    pub kx: usize,
    pub ky: usize,
    pub kz: usize,
    pub sx: f32,
    pub sy: f32,
    pub sz: f32,
    /// The origin's components in the order kx, ky, kz.
    pub org_k: [f32; 3],
    /// A power of two ≥ 1: the walk's `t` per unit of the ray's (see the module doc).
    pub t_scale: f32,
}

/// The largest direction component a walk takes as given (2^16): grid space then stays within
/// f32 (below 2^126) for cells down to 2^-110 of a unit, the least box
/// ([`crate::geometry::MIN_BOX_EXTENT`], 2^-100) in [`crate::geometry::MAX_AXIS_RES`] cells.
const WALK_DIR_MAX: f32 = 65536.0;

impl PreparedRay {
    /// The direction the walks take: `dir / t_scale` (exact, a power of two).
    #[inline(always)]
    pub fn walk_dir(&self) -> Vec3 {
        self.dir * self.inv_t_scale()
    }

    /// 1 / `t_scale`, exact, from its exponent bits (2^k → 2^-k with k ≤ 112): no division.
    #[inline(always)]
    fn inv_t_scale(&self) -> f32 {
        f32::from_bits(0x7f00_0000 - self.t_scale.to_bits())
    }

    /// The ray's `t` in the walk's units (exact; an overflow to ±inf only widens a bound).
    #[inline(always)]
    pub fn walk_t(&self, t: f32) -> f32 {
        t * self.t_scale
    }

    /// A walk's `t` back in the ray's units, rounded to f32 as a hit's `t` is: exact, unless it
    /// underflows (a huge direction across a tiny scene, whose hits' `t` round to zero), where it
    /// rounds to nearest. Rounding is monotone, so a hit beyond the walk's `t` has a ray `t` no
    /// smaller than this one.
    #[inline(always)]
    pub fn ray_t(&self, walk_t: f32) -> f32 {
        walk_t * self.inv_t_scale()
    }
}

/// [`PreparedRay::t_scale`] for direction `dir` (finite): 1 unless its largest component `m`
/// is 2^16 or more, else the power of two that brings `m` into [2^15, 2^16).
#[inline(always)]
fn walk_scale(dir: Vec3) -> f32 {
    let m = dir.abs().max_element();
    if m < WALK_DIR_MAX { 1.0 } else { f32::from_bits(((m.to_bits() >> 23) - 15) << 23) }
}

impl PreparedRay {
    /// Returns `None` for rays no triangle can be hit by: zero or non-finite direction,
    /// non-finite origin, NaN bounds or an empty `[tmin, tmax]`.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Option<PreparedRay> {
        let org = ray.o();
        let dir = ray.d();
        if !org.is_finite()
            || !dir.is_finite()
            || dir == Vec3::ZERO
            || ray.tmin.is_nan()
            || ray.tmax.is_nan()
            || ray.tmin > ray.tmax
        {
            return None;
        }
        // Dominant axis; ties go to the lower axis (deterministic, same rule on the GPU).
        let kz = argmax3(dir.abs().to_array());
        // The next two axes, swapped when the dominant component is negative (to keep the
        // winding). Chosen by arithmetic, not branches: a random ray's axes are unpredictable,
        // and a mispredicted branch costs more than this whole set-up.
        const NEXT: [usize; 3] = [1, 2, 0];
        let (d, o) = (dir.to_array(), org.to_array());
        let (k1, k2) = (NEXT[kz % 3], NEXT[NEXT[kz % 3]]);
        let swap = ((d[kz % 3] < 0.0) as usize).wrapping_neg() & (k1 ^ k2);
        let (kx, ky) = (k1 ^ swap, k2 ^ swap);
        let sz = 1.0 / d[kz % 3];
        Some(PreparedRay {
            org,
            dir,
            tmin: ray.tmin,
            tmax: ray.tmax,
            kx,
            ky,
            kz,
            sx: d[kx % 3] * sz,
            sy: d[ky % 3] * sz,
            sz,
            org_k: [o[kx % 3], o[ky % 3], o[kz % 3]],
            t_scale: walk_scale(dir),
        })
    }
}

/// Index of the largest of three values (the dominant axis); ties go to the lowest axis, as in
/// `argmax3` of shaders/shared/ray.wgsl.
#[inline]
pub fn argmax3<T: PartialOrd>(v: [T; 3]) -> usize {
    // `if x wins { 0 } else if y >= z { 1 } else { 2 }`, without branches (see `PreparedRay`).
    let x_wins = (v[0] >= v[1]) & (v[0] >= v[2]);
    let y_wins = (v[1] >= v[2]) as usize;
    (!x_wins) as usize * (2 - y_wins)
}
