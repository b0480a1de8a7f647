//! Keyframe interpolation, the glTF 2.0 rules: `STEP` holds a key until the next one, `LINEAR`
//! interpolates (rotations by the specification's quaternion slerp, shortest path), and
//! `CUBICSPLINE` evaluates the Hermite curve from each key's in-tangent, value and out-tangent,
//! tangents scaled by the key interval. Times before the first key or after the last clamp to
//! it. Rotations are normalised after interpolation.

use glam::DQuat;

/// How a sampler interpolates between its keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

impl From<gltf::animation::Interpolation> for Interpolation {
    fn from(i: gltf::animation::Interpolation) -> Interpolation {
        match i {
            gltf::animation::Interpolation::Step => Interpolation::Step,
            gltf::animation::Interpolation::Linear => Interpolation::Linear,
            gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
        }
    }
}

/// One animation sampler: key times and `width` values per key (three per key, tangents
/// around the value, for `CUBICSPLINE`). Validated on load: times finite and strictly
/// increasing, at least one key (two for `CUBICSPLINE`), and the value count matching.
#[derive(Clone, Debug)]
pub(crate) struct Sampler {
    pub interpolation: Interpolation,
    pub times: Vec<f64>,
    pub values: Vec<f64>,
    pub width: usize,
}

impl Sampler {
    /// The first and last key times.
    pub fn range(&self) -> (f64, f64) {
        (self.times[0], self.times[self.times.len() - 1])
    }

    /// The first key whose value (as a quaternion, `width` 4) has length zero: a rotation no
    /// normalisation can give a direction (NaN in every vertex it moves).
    pub fn zero_quaternion_key(&self) -> Option<usize> {
        (0..self.times.len()).find(|&k| quat(self.value(k)).length_squared() == 0.0)
    }

    /// Element `k`'s value (the middle of its triple for `CUBICSPLINE`).
    fn value(&self, k: usize) -> &[f64] {
        let w = self.width;
        match self.interpolation {
            Interpolation::CubicSpline => &self.values[(3 * k + 1) * w..(3 * k + 2) * w],
            _ => &self.values[k * w..(k + 1) * w],
        }
    }

    /// The value at time `t` into `out` (`width` numbers). `rotation`: the values are
    /// quaternions (x, y, z, w), slerped and normalised.
    pub fn sample(&self, t: f64, rotation: bool, out: &mut [f64]) {
        let n = self.times.len();
        let w = self.width;
        debug_assert_eq!(out.len(), w);
        // Keys k and k + 1 around t; clamped outside the keys.
        let after = self.times.partition_point(|&x| x <= t);
        if after == 0 || after == n || t.is_nan() {
            let k = if after == 0 || t.is_nan() { 0 } else { n - 1 };
            out.copy_from_slice(self.value(k));
            return;
        }
        let k = after - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let s = (t - t0) / dt;
        match self.interpolation {
            Interpolation::Step => out.copy_from_slice(self.value(k)),
            Interpolation::Linear if rotation => {
                let q = slerp(quat(self.value(k)), quat(self.value(k + 1)), s);
                out.copy_from_slice(&q.to_array());
            }
            Interpolation::Linear => {
                let (a, b) = (self.value(k), self.value(k + 1));
                for i in 0..w {
                    out[i] = a[i] + (b[i] - a[i]) * s;
                }
            }
            Interpolation::CubicSpline => {
                let v0 = self.value(k);
                let b0 = &self.values[(3 * k + 2) * w..(3 * k + 3) * w];
                let a1 = &self.values[(3 * (k + 1)) * w..(3 * (k + 1) + 1) * w];
                let v1 = self.value(k + 1);
                let (s2, s3) = (s * s, s * s * s);
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = (s3 - 2.0 * s2 + s) * dt;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = (s3 - s2) * dt;
                for i in 0..w {
                    out[i] = h00 * v0[i] + h10 * b0[i] + h01 * v1[i] + h11 * a1[i];
                }
                if rotation {
                    out.copy_from_slice(&quat(out).normalize().to_array());
                }
            }
        }
    }
}

fn quat(v: &[f64]) -> DQuat {
    DQuat::from_xyzw(v[0], v[1], v[2], v[3])
}

/// The glTF specification's quaternion slerp (Appendix: interpolation): shortest path, a
/// normalised lerp when the keys are within 0.9995 of each other.
pub(crate) fn slerp(a: DQuat, b: DQuat, s: f64) -> DQuat {
    let mut b = b;
    let mut d = a.dot(b);
    if d < 0.0 {
        b = -b;
        d = -d;
    }
    if d > 0.9995 {
        return (a * (1.0 - s) + b * s).normalize();
    }
    let theta0 = d.acos();
    let theta = s * theta0;
    let (sin_t, sin_t0) = (theta.sin(), theta0.sin());
    let ka = theta.cos() - d * sin_t / sin_t0;
    let kb = sin_t / sin_t0;
    (a * ka + b * kb).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sampler(interpolation: Interpolation, times: &[f64], values: &[f64], width: usize) -> Sampler {
        Sampler { interpolation, times: times.to_vec(), values: values.to_vec(), width }
    }

    fn at(s: &Sampler, t: f64, rotation: bool) -> Vec<f64> {
        let mut out = vec![0.0; s.width];
        s.sample(t, rotation, &mut out);
        out
    }

    #[test]
    fn step_linear_and_clamping() {
        let step = sampler(Interpolation::Step, &[1.0, 2.0, 3.0], &[10.0, 20.0, 30.0], 1);
        assert_eq!(at(&step, 0.0, false), [10.0]);
        assert_eq!(at(&step, 1.99, false), [10.0]);
        assert_eq!(at(&step, 2.0, false), [20.0]);
        assert_eq!(at(&step, 9.0, false), [30.0]);
        let lin = sampler(Interpolation::Linear, &[1.0, 2.0, 3.0], &[10.0, 20.0, 40.0], 1);
        assert_eq!(at(&lin, 1.5, false), [15.0]);
        assert_eq!(at(&lin, 2.25, false), [25.0]);
        assert_eq!(at(&lin, -1.0, false), [10.0]);
        assert_eq!(at(&lin, 4.0, false), [40.0]);
        assert_eq!(at(&lin, f64::NAN, false), [10.0]);
    }

    #[test]
    fn slerp_takes_the_short_way_at_constant_speed() {
        let a = DQuat::IDENTITY;
        let b = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
        let q = slerp(a, b, 0.5);
        assert!(q.abs_diff_eq(DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4), 1e-12));
        // -b is the same rotation: the short way gives the same answer.
        assert!(slerp(a, -b, 0.5).abs_diff_eq(q, 1e-12) || slerp(a, -b, 0.5).abs_diff_eq(-q, 1e-12));
        let lin = sampler(Interpolation::Linear, &[0.0, 1.0], &[a.to_array(), b.to_array()].concat(), 4);
        let r = at(&lin, 0.25, true);
        assert!(quat(&r).abs_diff_eq(DQuat::from_rotation_z(std::f64::consts::PI / 8.0), 1e-12));
    }

    #[test]
    fn cubic_spline_is_the_hermite_curve() {
        // Keys at 0 and 2 with values 0 and 1, out-tangent 1 at the first key, in-tangent 0 at
        // the second: p(s) = h10 * 2 * 1 + h01 * 1 with s = t / 2.
        let v = [9.0, 0.0, 1.0, 0.0, 1.0, 9.0];
        let c = sampler(Interpolation::CubicSpline, &[0.0, 2.0], &v, 1);
        for t in [0.0, 0.5, 1.0, 1.5, 2.0] {
            let s: f64 = t / 2.0;
            let want = (s * s * s - 2.0 * s * s + s) * 2.0 + (-2.0 * s * s * s + 3.0 * s * s);
            assert!((at(&c, t, false)[0] - want).abs() < 1e-12, "t = {t}");
        }
        assert_eq!(at(&c, 5.0, false), [1.0]);
    }
}
