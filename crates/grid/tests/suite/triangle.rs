//! The watertight triangle test: hits are geometrically real, misses are real misses.

use glam::{DVec3, Vec3};
use gridrt_grid::ray::PreparedRay;
use gridrt_grid::triangle::intersect;
use gridrt_scene::Ray;
use gridrt_scene::rng::Rng;

/// Distance from `p` to triangle `t` (f64).
fn dist_to_triangle(p: DVec3, t: &[Vec3; 3]) -> f64 {
    let (a, b, c) = (t[0].as_dvec3(), t[1].as_dvec3(), t[2].as_dvec3());
    let n = (b - a).cross(c - a);
    if n.length_squared() > 0.0 {
        let nn = n.normalize();
        let q = p - nn * nn.dot(p - a);
        let inside = [(a, b), (b, c), (c, a)].iter().all(|(e0, e1)| (*e1 - *e0).cross(q - *e0).dot(n) >= 0.0);
        if inside {
            return (p - q).length();
        }
    }
    let seg = |x: DVec3, y: DVec3| {
        let d = y - x;
        let s = if d.length_squared() > 0.0 { ((p - x).dot(d) / d.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
        (p - (x + d * s)).length()
    };
    seg(a, b).min(seg(b, c)).min(seg(c, a))
}

#[test]
fn nearly_edge_on_triangle_far_away_is_a_miss() {
    // Found on Crytek Sponza: in f32 both products of two edge functions round to the same
    // value, U = V = 0, and the naive test reported a hit ~370 units from the triangle.
    let ray = Ray {
        origin: [270.99924, 291.8276, 499.8605],
        tmin: 0.0,
        dir: [-0.7298839, 0.0066349804, -0.82833403],
        tmax: f32::INFINITY,
    };
    let tri = [
        Vec3::new(51.353, 11.4668, -22.1363),
        Vec3::new(51.3435, 11.5082, -22.1072),
        Vec3::new(51.3663, 11.4812, -22.1072),
    ];
    assert_eq!(intersect(&PreparedRay::new(&ray).unwrap(), &tri), None);
}

#[test]
fn every_hit_lies_on_its_triangle() {
    // Small triangles far from the origin, rays aimed at vertices, edges and near-misses:
    // a reported hit point must be within rounding distance of the triangle.
    let mut rng = Rng::new(5);
    let mut hits = 0;
    for _ in 0..200_000 {
        let scale = 10f32.powf(rng.range(-3.0, 1.0));
        let c = Vec3::new(rng.range(-100.0, 100.0), rng.range(-100.0, 100.0), rng.range(-100.0, 100.0));
        let t = [c, c + rng.unit_vector() * scale, c + rng.unit_vector() * scale];
        let o = c + rng.unit_vector() * rng.range(1.0, 800.0);
        let target = match rng.below(3) {
            0 => t[rng.below(3) as usize],
            1 => t[0] + (t[1] - t[0]) * rng.f32(),
            _ => c + rng.unit_vector() * scale * 2.0,
        };
        let ray = Ray::new(o, target - o, 0.0, f32::INFINITY);
        if let Some(h) = intersect(&PreparedRay::new(&ray).unwrap(), &t) {
            hits += 1;
            let p = ray.o().as_dvec3() + ray.d().as_dvec3() * h.t as f64;
            let tol = 1e-5 * (o - c).length() as f64 + 1e-5;
            let d = dist_to_triangle(p, &t);
            assert!(d <= tol, "hit {h:?} is {d} from the triangle (tol {tol}); ray {ray:?} tri {t:?}");
            assert!(h.u >= 0.0 && h.v >= 0.0 && h.u + h.v <= 1.0 + 1e-6, "{h:?}");
        }
    }
    assert!(hits > 50_000, "{hits}");
}

/// The f32 pre-filter of the edge functions only ever rejects what the exact signs reject:
/// random corners of every magnitude (subnormal to near overflow), nearly collinear corners,
/// corners on a line through the origin and exact zeros; and it does reject most misses.
#[test]
fn f32_edge_filter_never_rejects_an_exact_inside() {
    use gridrt_grid::triangle::certainly_outside;
    let mut rng = Rng::new(5);
    let exact_outside = |a: [f32; 2], b: [f32; 2], c: [f32; 2]| {
        let e = |x: f32, y: f32, z: f32, w: f32| x as f64 * y as f64 - z as f64 * w as f64;
        let (u, v, w) = (e(c[0], b[1], c[1], b[0]), e(a[0], c[1], a[1], c[0]), e(b[0], a[1], b[1], a[0]));
        (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)
    };
    let (mut rejected, mut outside, mut cases) = (0u64, 0u64, 0u64);
    for i in 0..400_000 {
        let scale = 2f32.powi(rng.below(280) as i32 - 150);
        let mut p = || [rng.range(-1.0, 1.0) * scale, rng.range(-1.0, 1.0) * scale];
        let (mut a, mut b, mut c) = (p(), p(), p());
        match i % 5 {
            // Nearly collinear: c a hair off the line a–b.
            1 => {
                let s = rng.f32();
                c = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]) * (1.0 + 1e-7)];
            }
            // On a line through the origin: an edge function is (nearly) zero.
            2 => b = [a[0] * -0.5, a[1] * -0.5],
            // Exact zeros and shared coordinates.
            3 => {
                a[0] = 0.0;
                c[1] = b[1];
            }
            // Huge and tiny corners together.
            4 => c = [c[0] * 1e30, c[1] * 1e-30],
            _ => {}
        }
        let ex = exact_outside(a, b, c);
        let f = certainly_outside(a, b, c);
        assert!(!f || ex, "filter rejected an inside: {a:?} {b:?} {c:?}");
        // Its use: plain corners at scales where products neither overflow nor underflow.
        if i % 5 == 0 && scale.abs().log2().abs() < 60.0 {
            rejected += f as u64;
            outside += ex as u64;
            cases += 1;
        }
    }
    println!("f32 filter: {rejected} of {outside} exact misses rejected ({cases} plain cases)");
    assert!(
        rejected as f64 > 0.99 * outside as f64,
        "the filter should decide nearly every miss: {rejected} of {outside}"
    );
}
