//! The binary ray and hit file formats, and the ray sets `gridrt rays` generates.
//!
//! Ray file: no header, 32 bytes per ray, little-endian `f32 × 8`: `ox oy oz tmin dx dy dz
//! tmax`. Directions need not be normalised; `t` is in units of the direction's length.
//! Hits file: 16 bytes per ray: `f32 t`, `u32 triangle`, `f32 u`, `f32 v`; a miss is
//! `t = +inf`, `triangle = 0xFFFF_FFFF`, `u = v = 0`.

use std::path::Path;

use bytemuck::Pod;
use glam::Vec3;

use crate::camera::Camera;
use crate::error::RayFileError;
use crate::file_read::{ReadFault, read_regular_file};
use crate::mesh::{Aabb, Mesh};
use crate::ray::{Hit, Ray};
use crate::rng::Rng;

fn records_from_le<T: Pod>(bytes: &[u8], name: &str, what: &'static str) -> Result<Vec<T>, RayFileError> {
    let record = std::mem::size_of::<T>();
    if !bytes.len().is_multiple_of(record) {
        return Err(RayFileError::BadSize { source_name: name.into(), len: bytes.len() as u64, record, what });
    }
    // Every field is 4 bytes: decode each word little-endian so the format is the same on
    // big-endian hosts.
    let mut out = vec![T::zeroed(); bytes.len() / record];
    let words: &mut [u32] = bytemuck::cast_slice_mut(&mut out);
    for (w, b) in words.iter_mut().zip(bytes.chunks_exact(4)) {
        *w = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    }
    Ok(out)
}

fn records_to_le<T: Pod>(records: &[T]) -> Vec<u8> {
    let words: &[u32] = bytemuck::cast_slice(records);
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

pub fn rays_from_bytes(bytes: &[u8], name: &str) -> Result<Vec<Ray>, RayFileError> {
    records_from_le(bytes, name, "ray")
}
pub fn rays_to_bytes(rays: &[Ray]) -> Vec<u8> {
    records_to_le(rays)
}
pub fn hits_from_bytes(bytes: &[u8], name: &str) -> Result<Vec<Hit>, RayFileError> {
    records_from_le(bytes, name, "hit")
}
pub fn hits_to_bytes(hits: &[Hit]) -> Vec<u8> {
    records_to_le(hits)
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> RayFileError + '_ {
    move |err| RayFileError::Io { source_name: path.display().to_string(), err }
}
/// Reads a ray file: a regular file (not a device or pipe) within the default load budget.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>, RayFileError> {
    rays_from_bytes(&read_bounded(path)?, &path.display().to_string())
}

/// A regular file's bytes, refused above [`crate::load_budget::default_max_bytes`] (each
/// record read is also a record written).
fn read_bounded(path: &Path) -> Result<Vec<u8>, RayFileError> {
    let limit = crate::load_budget::default_max_bytes();
    let source_name = path.display().to_string();
    read_regular_file(path, limit).map_err(|fault| match fault {
        ReadFault::Io(err) => RayFileError::Io { source_name, err },
        ReadFault::NotAFile => RayFileError::NotAFile { source_name },
        ReadFault::TooLarge { len } => RayFileError::TooLarge { source_name, len, limit },
    })
}
pub fn write_rays(path: &Path, rays: &[Ray]) -> Result<(), RayFileError> {
    std::fs::write(path, rays_to_bytes(rays)).map_err(io_err(path))
}
pub fn read_hits(path: &Path) -> Result<Vec<Hit>, RayFileError> {
    hits_from_bytes(&read_bounded(path)?, &path.display().to_string())
}
pub fn write_hits(path: &Path, hits: &[Hit]) -> Result<(), RayFileError> {
    std::fs::write(path, hits_to_bytes(hits)).map_err(io_err(path))
}

/// `count` rays with origins uniform in `bounds` grown by 10% and directions uniform on the
/// sphere, `[0, inf)`: the "random rays" of the survey's cost model and of the BVH benchmark.
pub fn random_rays(bounds: &Aabb, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    let pad = bounds.extent() * 0.05;
    let (lo, hi) = (bounds.min - pad, bounds.max + pad);
    (0..count)
        .map(|_| {
            let o = Vec3::new(rng.range(lo.x, hi.x), rng.range(lo.y, hi.y), rng.range(lo.z, hi.z));
            Ray::new(o, rng.unit_vector(), 0.0, f32::INFINITY)
        })
        .collect()
}

/// A whole image of about `count` pixels at `aspect` (width / height): its width and height,
/// each at least 1 (the rays of an image whose packets tile it).
pub fn image_size(count: usize, aspect: f64) -> (u32, u32) {
    let width = ((count as f64 * aspect).sqrt().round() as u32).max(1);
    (width, (count as u32 / width).max(1))
}

/// Image size with about `count` pixels at 4:3, and the rays of the first `count` pixels in
/// row-major order (primary rays).
pub fn camera_rays(camera: &Camera, count: usize) -> Vec<Ray> {
    let w = ((count as f64 * 4.0 / 3.0).sqrt().ceil() as u32).max(1);
    let h = (count as u32).div_ceil(w).max(1);
    image_rays(camera, w, h).into_iter().take(count).collect()
}

/// One ray per pixel of a `width`×`height` image, row-major from the top-left.
pub fn image_rays(camera: &Camera, width: u32, height: u32) -> Vec<Ray> {
    (0..height).flat_map(|y| (0..width).map(move |x| camera.ray(x, y, width, height))).collect()
}

/// Watertightness probes: rays from `origin` aimed exactly at mesh vertices, at points on
/// edges (midpoints and random points) and in random directions. From a point inside a
/// closed mesh every one of them must hit.
pub fn inside_rays(mesh: &Mesh, origin: Vec3, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    let n = mesh.indices.len() as u64;
    (0..count)
        .map(|i| {
            let dir = if n == 0 {
                rng.unit_vector()
            } else {
                let tri = mesh.triangle(rng.below(n) as usize);
                let k = rng.below(3) as usize;
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                match i % 4 {
                    0 => a - origin,
                    1 => (a + b) * 0.5 - origin,
                    2 => a + (b - a) * rng.f32() - origin,
                    _ => rng.unit_vector(),
                }
            };
            let dir = if dir == Vec3::ZERO { Vec3::X } else { dir };
            Ray::new(origin, dir, 0.0, f32::INFINITY)
        })
        .collect()
}
