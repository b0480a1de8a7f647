//! Ray and hit files: exact little-endian layout, size checks, and the ray generators.

use glam::Vec3;
use gridrt_scene::RayFileError;
use gridrt_scene::rays::*;
use gridrt_scene::{Aabb, Camera, Hit, Ray};

#[test]
fn ray_file_layout_is_eight_le_floats() {
    let r = Ray::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(-4.0, 5.0, 6.5), 0.25, f32::INFINITY);
    let b = rays_to_bytes(&[r]);
    assert_eq!(b.len(), 32);
    let f: Vec<f32> = b.chunks(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    assert_eq!(f, vec![1.0, 2.0, 3.0, 0.25, -4.0, 5.0, 6.5, f32::INFINITY]);
    assert_eq!(rays_from_bytes(&b, "x").unwrap(), vec![r]);
}

#[test]
fn hit_file_layout_and_miss_encoding() {
    let h = [Hit { t: 1.5, triangle: 7, u: 0.25, v: 0.5 }, Hit::MISS];
    let b = hits_to_bytes(&h);
    assert_eq!(b.len(), 32);
    assert_eq!(&b[0..4], &1.5f32.to_le_bytes());
    assert_eq!(&b[4..8], &7u32.to_le_bytes());
    assert_eq!(&b[16..20], &f32::INFINITY.to_le_bytes());
    assert_eq!(&b[20..24], &[0xFF; 4]);
    assert_eq!(hits_from_bytes(&b, "x").unwrap(), h.to_vec());
}

#[test]
fn wrong_sizes_are_errors() {
    for n in [1usize, 31, 33, 100] {
        let e = rays_from_bytes(&vec![0; n], "bad.bin").unwrap_err();
        assert!(matches!(e, RayFileError::BadSize { len, record: 32, .. } if len == n as u64), "{e}");
        assert!(e.to_string().contains("bad.bin"));
    }
    assert!(hits_from_bytes(&[0; 17], "h").is_err());
    assert!(rays_from_bytes(&[], "empty").unwrap().is_empty());
}

#[test]
fn generators_produce_what_they_promise() {
    let b = Aabb { min: Vec3::ZERO, max: Vec3::new(2.0, 1.0, 1.0) };
    let r = random_rays(&b, 1000, 1);
    assert_eq!(r, random_rays(&b, 1000, 1));
    assert!(r.iter().all(|r| (r.d().length() - 1.0).abs() < 1e-5 && r.tmin == 0.0 && r.tmax == f32::INFINITY));
    let cam = Camera::fit(&b, 4.0 / 3.0);
    let c = camera_rays(&cam, 1200);
    assert_eq!(c.len(), 1200);
    assert!(c.iter().all(|r| r.o() == cam.eye));
    // The auto camera sees the whole box: the corners project inside the image.
    let fwd = (cam.target - cam.eye).normalize();
    for i in 0..8 {
        let p = Vec3::new(if i & 1 != 0 { 2.0 } else { 0.0 }, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32);
        let v = (p - cam.eye).normalize();
        assert!(v.dot(fwd) > (cam.vfov_deg.to_radians() * 0.5).cos(), "corner {p} outside the view");
    }
    assert!(Camera::parse("0,0,5,0,0,0,45").is_ok());
    assert!(Camera::parse("0,0,5,0,0,0").is_err());
    assert!(Camera::parse("0,0,0,0,0,0,45").is_err());
}
