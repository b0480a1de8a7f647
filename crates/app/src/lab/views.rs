//! The ray sets a benchmark traces on a scene: a camera the model fills (framed), a view from
//! inside for architectural scenes (interior), and random rays in the bounds. The camera that
//! frames the bounds (`--camera auto`) sees mostly background on a scanned model, so it would
//! mostly time misses; the framed camera is aimed and narrowed until most of its rays hit.

use glam::Vec3;
use gridrt_grid::AnyGrid;
use gridrt_grid::trace::TraceOptions;
#[cfg(not(target_arch = "wasm32"))]
use gridrt_grid::{GridConfig, structure};
use gridrt_scene::rays::image_rays;
#[cfg(not(target_arch = "wasm32"))]
use gridrt_scene::rays::{image_size, random_rays};
use gridrt_scene::{Aabb, Camera, Hit, Ray};
#[cfg(not(target_arch = "wasm32"))]
use serde::Serialize;

#[cfg(not(target_arch = "wasm32"))]
use super::scenes::LabScene;
use crate::cli::CameraArg;

/// The share of a framed camera's probe rays that must hit (the full-size image gets about the
/// same share; the issue asks for at least 0.7).
pub const FRAMED_HIT_SHARE: f64 = 0.75;

/// Which rays a set holds.
#[cfg(not(target_arch = "wasm32"))]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RaySet {
    /// Camera rays of [`framed_camera`].
    Framed,
    /// Camera rays of [`interior_camera`] (architectural scenes).
    Interior,
    /// Random origins in the bounds, random directions.
    Random,
}

#[cfg(not(target_arch = "wasm32"))]
impl RaySet {
    pub fn name(self) -> &'static str {
        match self {
            RaySet::Framed => "framed",
            RaySet::Interior => "interior",
            RaySet::Random => "random",
        }
    }
}

/// One ray set of a scene: its rays, and the width of their image when they are one (the camera
/// sets, row-major, so packets can tile them).
#[cfg(not(target_arch = "wasm32"))]
pub struct RayBatch {
    pub set: RaySet,
    pub rays: Vec<Ray>,
    pub width: Option<usize>,
}

/// The ray sets of `sc`, about `count` rays each: framed and interior (architectural scenes only)
/// as whole 4:3 images, and random rays. `probe` is a structure over `sc.tris` the framing
/// traces its probe images with.
#[cfg(not(target_arch = "wasm32"))]
pub fn ray_sets(sc: &LabScene, probe: &AnyGrid, count: usize) -> Vec<RayBatch> {
    let (w, h) = image_size(count, 4.0 / 3.0);
    let image = |set, cam: &Camera| RayBatch { set, rays: image_rays(cam, w, h), width: Some(w as usize) };
    let framed = framed_camera(&sc.tris, &sc.bounds, probe, w as f32 / h as f32);
    let mut sets = vec![image(RaySet::Framed, &framed)];
    if sc.kind.starts_with("architectural") {
        sets.push(image(RaySet::Interior, &interior_camera(&sc.tris, &sc.bounds, probe)));
    }
    sets.push(RayBatch { set: RaySet::Random, rays: random_rays(&sc.bounds, count, 7), width: None });
    sets
}

/// The flat grid the framing probes with.
#[cfg(not(target_arch = "wasm32"))]
pub fn probe_grid(tris: &[[Vec3; 3]]) -> anyhow::Result<AnyGrid> {
    Ok(structure::build(tris, &GridConfig::default())?.0)
}

/// Share of `hits` that hit something.
pub fn hit_share(hits: &[Hit]) -> f64 {
    hits.iter().filter(|h| h.is_hit()).count() as f64 / hits.len().max(1) as f64
}

/// A `w`×`h` probe image of `cam` traced through `probe`: its rays and their hits.
fn probe_image(tris: &[[Vec3; 3]], probe: &AnyGrid, cam: &Camera, w: u32, h: u32) -> (Vec<Ray>, Vec<Hit>) {
    let rays = image_rays(cam, w, h);
    let opts = TraceOptions::MAILBOX;
    let (hits, _) = probe.trace_batch(tris, &rays, opts, true);
    (rays, hits)
}

/// A camera for images of `aspect` (width / height) that the model fills: from
/// [`Camera::fit`]'s eye, turned towards the centre of the hit pixels of a small probe image and
/// narrowed to their extent (or zoomed in when they already span the image), until
/// [`FRAMED_HIT_SHARE`] of the probe rays hit. An empty probe keeps the camera it has.
pub fn framed_camera(tris: &[[Vec3; 3]], bounds: &Aabb, probe: &AnyGrid, aspect: f32) -> Camera {
    let (w, h) = (96u32, ((96.0 / aspect).round() as u32).clamp(8, 960));
    let mut cam = Camera::fit(bounds, aspect);
    for _ in 0..16 {
        let (_, hits) = probe_image(tris, probe, &cam, w, h);
        // The hit pixels' box in image coordinates, [-1, 1] on both axes, y up.
        let (mut lo, mut hi) = (glam::Vec2::splat(1.0), glam::Vec2::splat(-1.0));
        for (i, _) in hits.iter().enumerate().filter(|(_, h)| h.is_hit()) {
            let (x, y) = ((i as u32 % w) as f32, (i as u32 / w) as f32);
            let p = glam::Vec2::new((x + 0.5) / w as f32 * 2.0 - 1.0, 1.0 - (y + 0.5) / h as f32 * 2.0);
            (lo, hi) = (lo.min(p), hi.max(p));
        }
        let share = hit_share(&hits);
        if share == 0.0 || share >= FRAMED_HIT_SHARE {
            break;
        }
        let (right, up, fwd) = cam.basis();
        let half_v = (cam.vfov_deg.to_radians() * 0.5).tan();
        let half_h = half_v * aspect;
        let centre = (lo + hi) * 0.5;
        let dir = (fwd + right * (centre.x * half_h) + up * (centre.y * half_v)).normalize();
        // Half the box, plus a pixel, in tangent units.
        let half_box = (hi - lo) * 0.5 + glam::Vec2::new(1.0 / w as f32, 1.0 / h as f32);
        let mut new_half_v = (half_box.y * half_v).max(half_box.x * half_h / aspect);
        if new_half_v > 0.95 * half_v {
            new_half_v = 0.85 * half_v;
        }
        let dist = gridrt_scene::scaled::length_scaled(cam.target - cam.eye);
        cam =
            Camera { target: cam.eye + dir * dist, vfov_deg: (2.0 * new_half_v.atan()).to_degrees().max(0.05), ..cam };
    }
    cam
}

/// The camera `arg` names for images of `aspect` (width / height) of `tris`, probing `probe` (a
/// structure over them) for the framed and interior views.
pub fn camera(arg: CameraArg, tris: &[[Vec3; 3]], bounds: &Aabb, probe: &AnyGrid, aspect: f32) -> Camera {
    match arg {
        CameraArg::Auto => Camera::fit(bounds, aspect),
        CameraArg::Framed => framed_camera(tris, bounds, probe, aspect),
        CameraArg::Interior => interior_camera(tris, bounds, probe),
        CameraArg::At(cam) => cam,
    }
}

/// A view along an architectural scene from inside, looking down its longer horizontal axis
/// (glTF's +y is up) with a 60° field of view: of the eyes on that axis' centre line between a
/// tenth and half of the way in, at 15% or 30% of the height, the one whose small probe image
/// sees deepest (the largest median hit distance, a miss counting as 0: a wall in front of the
/// eye or an open side both see nothing).
pub fn interior_camera(tris: &[[Vec3; 3]], bounds: &Aabb, probe: &AnyGrid) -> Camera {
    let (lo, ext, c) = (bounds.min, bounds.max - bounds.min, bounds.center());
    let along_x = ext.x >= ext.z;
    let camera = |f: f32, h: f32| {
        let y = lo.y + h * ext.y;
        let (eye, target) = if along_x {
            (Vec3::new(lo.x + f * ext.x, y, c.z), Vec3::new(bounds.max.x, y, c.z))
        } else {
            (Vec3::new(c.x, y, lo.z + f * ext.z), Vec3::new(c.x, y, bounds.max.z))
        };
        Camera { eye, target, up: Vec3::Y, vfov_deg: 60.0 }
    };
    let depth = |cam: &Camera| {
        let (rays, hits) = probe_image(tris, probe, cam, 32, 24);
        // A miss counts as no depth: looking out of an open side is not looking along the inside.
        let mut d: Vec<f32> =
            hits.iter().zip(&rays).map(|(h, r)| if h.is_hit() { h.t * r.d().length() } else { 0.0 }).collect();
        d.sort_by(f32::total_cmp);
        d[d.len() / 2]
    };
    // Each candidate's probe is traced once.
    let candidates = [0.1f32, 0.2, 0.3, 0.4, 0.5].into_iter().flat_map(|f| [0.15f32, 0.3].map(|h| camera(f, h)));
    candidates.map(|cam| (depth(&cam), cam)).max_by(|a, b| a.0.total_cmp(&b.0)).expect("candidates").1
}

#[cfg(test)]
mod tests {
    use gridrt_scene::procedural::{SceneKind, generate};

    use super::*;

    fn share(tris: &[[Vec3; 3]], probe: &AnyGrid, cam: &Camera) -> f64 {
        hit_share(&probe_image(tris, probe, cam, 64, 48).1)
    }

    /// The framed camera fills its image with the model (the bounds-framing camera does not),
    /// and the interior view of a closed building sees walls in every direction.
    #[test]
    fn framed_and_interior_views_see_the_model() {
        for kind in [SceneKind::Sphereflake, SceneKind::Mountain] {
            let tris = generate(kind, 2, 1).mesh.triangles();
            let bounds = gridrt_grid::triangle_bounds_with(&tris, false);
            let probe = probe_grid(&tris).unwrap();
            let fit = share(&tris, &probe, &Camera::fit(&bounds, 4.0 / 3.0));
            let framed = share(&tris, &probe, &framed_camera(&tris, &bounds, &probe, 4.0 / 3.0));
            assert!(framed >= 0.7 && framed > fit, "{kind:?}: framed {framed}, fit {fit}");
        }
        // A closed box of 12 triangles: from inside, every ray hits.
        let (lo, hi) = (Vec3::new(-4.0, 0.0, -1.0), Vec3::new(4.0, 2.0, 1.0));
        let c = |i: u32| {
            Vec3::new(
                [lo.x, hi.x][(i & 1) as usize],
                [lo.y, hi.y][(i >> 1 & 1) as usize],
                [lo.z, hi.z][(i >> 2) as usize],
            )
        };
        let quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
        let tris: Vec<[Vec3; 3]> =
            quads.iter().flat_map(|q| [[c(q[0]), c(q[1]), c(q[2])], [c(q[0]), c(q[2]), c(q[3])]]).collect();
        let bounds = gridrt_grid::triangle_bounds_with(&tris, false);
        let probe = probe_grid(&tris).unwrap();
        let cam = interior_camera(&tris, &bounds, &probe);
        assert!(share(&tris, &probe, &cam) == 1.0, "{cam:?}");
        assert!((cam.target - cam.eye).x > 0.0, "looks along the longer axis: {cam:?}");
    }
}
