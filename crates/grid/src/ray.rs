//! A ray prepared once for the watertight triangle test (shaders/shared/ray.wgsl's
//! `PreparedRay`): the dominant direction axis, the shear, and the checks that refuse rays no
//! triangle can be hit by. Every structure and the brute-force reference start from it.

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
        let a = dir.abs();
        // Dominant axis; ties go to the lower axis (deterministic, same rule on the GPU).
        let kz = argmax3(a.to_array());
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding: swap when the dominant component is negative.
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / dir[kz];
        Some(PreparedRay {
            org,
            dir,
            tmin: ray.tmin,
            tmax: ray.tmax,
            kx,
            ky,
            kz,
            sx: dir[kx] * sz,
            sy: dir[ky] * sz,
            sz,
            org_k: [org[kx], org[ky], org[kz]],
        })
    }
}

/// Index of the largest of three values (the dominant axis); ties go to the lowest axis, as in
/// `argmax3` of shaders/shared/ray.wgsl.
#[inline]
pub fn argmax3<T: PartialOrd>(v: [T; 3]) -> usize {
    if v[0] >= v[1] && v[0] >= v[2] {
        0
    } else if v[1] >= v[2] {
        1
    } else {
        2
    }
}
