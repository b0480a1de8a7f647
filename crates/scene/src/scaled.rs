//! Lengths and directions of vectors at any scene scale. A vector's squared length leaves f32
//! beyond about 1.8e19 per component (overflow) and below about 1e-19 (underflow), where glam's
//! `length` and `normalize` give infinity, zero or NaN directions: a scene in light years or in
//! nanometres would get no camera, no shading and no shadow offset. Dividing by the largest
//! component first keeps both within a few ulps for every finite vector. The WGSL twins are
//! `length_scaled` and `normalize_scaled` in shaders/shared/render_bindings.wgsl.

use glam::Vec3;

/// The length of `v` without overflow or underflow (infinite or NaN for such components).
#[inline]
pub fn length_scaled(v: Vec3) -> f32 {
    let m = v.abs().max_element();
    if m > 0.0 && v.is_finite() { m * (v / m).length() } else { v.length() }
}

/// The unit vector along `v`, or zero when `v` is zero or not finite.
#[inline]
pub fn normalize_scaled(v: Vec3) -> Vec3 {
    let m = v.abs().max_element();
    if m > 0.0 && v.is_finite() { (v / m).normalize() } else { Vec3::ZERO }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At every scale from 1e-38 to 1e38 the length and the direction are those of the same
    /// vector at scale 1, to a few ulps; zero and non-finite vectors give no direction.
    #[test]
    fn lengths_and_directions_hold_at_every_scale() {
        let v = Vec3::new(3.0, -4.0, 12.0);
        for e in -38..=37 {
            let s = 10f32.powi(e);
            let w = v * s;
            let rel = (length_scaled(w) / s - 13.0).abs() / 13.0;
            assert!(rel < 1e-5, "scale 1e{e}: length {} (relative error {rel})", length_scaled(w));
            assert!((normalize_scaled(w) - v / 13.0).abs().max_element() < 1e-6, "scale 1e{e}");
        }
        assert_eq!(normalize_scaled(Vec3::ZERO), Vec3::ZERO);
        assert_eq!(normalize_scaled(Vec3::new(f32::INFINITY, 0.0, 0.0)), Vec3::ZERO);
        assert_eq!(normalize_scaled(Vec3::new(f32::NAN, 1.0, 0.0)), Vec3::ZERO);
        assert_eq!(length_scaled(Vec3::ZERO), 0.0);
        assert_eq!(length_scaled(Vec3::new(f32::INFINITY, 0.0, 0.0)), f32::INFINITY);
        // glam's own overflow and underflow, which these avoid.
        assert_eq!(Vec3::splat(1e20).length(), f32::INFINITY);
        assert_eq!(Vec3::splat(1e-25).length(), 0.0);
    }
}
