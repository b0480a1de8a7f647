//! Shared helpers: scenes, ray sets, the brute-force reference, the shared-scene folder.

use glam::Vec3;
use gridrt_grid::ray::PreparedRay;
use gridrt_grid::triangle::intersect;
use gridrt_grid::{BatchStats, brute, trace::trace_batch};
use gridrt_scene::procedural::{self, SceneKind};
use gridrt_scene::rays::{camera_rays, inside_rays, random_rays};
use gridrt_scene::rng::Rng;
use gridrt_scene::{Camera, Hit, Mesh, Ray};

pub use gridrt_testkit::{full_matrices, matrix_rays, shared_scenes};

/// Procedural test scenes small enough for a brute-force reference over 100k rays.
pub fn procedural_scenes() -> Vec<(String, procedural::Generated)> {
    vec![
        ("mountain".into(), procedural::generate(SceneKind::Mountain, 6, 1)),
        ("sphereflake".into(), procedural::sphereflake(1, 2)),
        ("particles".into(), procedural::generate(SceneKind::Particles, 20_000, 2)),
        ("slivers".into(), procedural::generate(SceneKind::Slivers, 3000, 3)),
        ("teapot-in-stadium".into(), procedural::generate(SceneKind::TeapotInStadium, 1, 4)),
    ]
}

/// `count` rays: 40% random, 35% camera (primary), 15% from inside points aimed at vertices and
/// edges, 10% random with clipped [tmin, tmax] and unnormalised directions.
pub fn mixed_rays(mesh: &Mesh, inside: &[Vec3], count: usize, seed: u64) -> Vec<Ray> {
    let b = mesh.bounds();
    let n_random = count * 40 / 100;
    let n_cam = count * 35 / 100;
    let n_inside = count * 15 / 100;
    let n_clip = count - n_random - n_cam - n_inside;
    let mut rays = random_rays(&b, n_random, seed);
    rays.extend(camera_rays(&Camera::fit(&b, 4.0 / 3.0), n_cam));
    let origins: Vec<Vec3> = if inside.is_empty() { vec![b.center()] } else { inside.to_vec() };
    let per = n_inside.div_ceil(origins.len()).max(1);
    let mut ins = Vec::new();
    for (i, o) in origins.iter().enumerate() {
        ins.extend(inside_rays(mesh, *o, per, seed + i as u64));
    }
    ins.truncate(n_inside);
    rays.extend(ins);
    let mut rng = Rng::new(seed ^ 0xABCD);
    for r in random_rays(&b, n_clip, seed + 99) {
        let scale = 10f32.powf(rng.range(-3.0, 3.0));
        let len = b.diagonal() / scale;
        let tmin = rng.range(0.0, 0.5) * len;
        let tmax = tmin + rng.range(0.0, 1.0) * len;
        rays.push(Ray::new(r.o(), r.d() * scale, tmin, tmax));
    }
    rays
}

/// Brute-force reference hits (all threads).
pub fn reference(tris: &[[Vec3; 3]], rays: &[Ray]) -> (Vec<Hit>, BatchStats) {
    let brute = brute::BruteForce::new(tris);
    trace_batch(rays, true, |r| brute.trace(r))
}

/// Asserts bit-exact equality of two hit lists, naming the first differences.
pub fn assert_same_hits(what: &str, rays: &[Ray], expected: &[Hit], got: &[Hit]) {
    assert_eq!(expected.len(), got.len());
    let bad = (0..expected.len()).filter(|&i| !expected[i].same_bits(&got[i]));
    fail_on(&format!("{what}: rays differ from brute force"), bad, rays, |i| {
        format!("expected {:?}, got {:?}", expected[i], got[i])
    });
}

/// Panics when `bad` names any ray, with their count and the first five (each described by
/// `show`).
fn fail_on(what: &str, bad: impl Iterator<Item = usize>, rays: &[Ray], show: impl Fn(usize) -> String) {
    let bad: Vec<usize> = bad.collect();
    if !bad.is_empty() {
        let first: Vec<String> = bad.iter().take(5).map(|&i| format!("ray {i} {:?}: {}", rays[i], show(i))).collect();
        panic!("{what}: {} of {}:\n{}", bad.len(), rays.len(), first.join("\n"));
    }
}

/// Asserts that an occlusion query's hits (`got`) agree with the closest hits (`expected`) on
/// whether each ray hits, and that every hit reported is a real one: its triangle's test gives
/// that `t` (bit for bit) within the ray's segment.
pub fn assert_same_occlusion(what: &str, tris: &[[Vec3; 3]], rays: &[Ray], expected: &[Hit], got: &[Hit]) {
    assert_eq!(expected.len(), got.len());
    let real = |r: &Ray, h: &Hit| {
        let Some(pr) = PreparedRay::new(r) else { return false };
        tris.get(h.triangle as usize).and_then(|t| intersect(&pr, t)).is_some_and(|th| th.t.to_bits() == h.t.to_bits())
    };
    let bad = (0..expected.len())
        .filter(|&i| expected[i].is_hit() != got[i].is_hit() || (got[i].is_hit() && !real(&rays[i], &got[i])));
    fail_on(&format!("{what}: occlusion answers are wrong"), bad, rays, |i| {
        format!("closest {:?}, any {:?}", expected[i], got[i])
    });
}

/// Segments that end just before, exactly at and just after each ray's closest hit in
/// `expected` (and the rays that miss, unchanged): the occlusion query's hardest cases.
pub fn segments_around_hits(rays: &[Ray], expected: &[Hit]) -> Vec<Ray> {
    let mut out = Vec::with_capacity(rays.len() * 3);
    for (r, h) in rays.iter().zip(expected) {
        if !h.is_hit() {
            out.push(*r);
            continue;
        }
        out.extend([h.t.next_down(), h.t, h.t.next_up()].map(|t| r.ending_at(t)));
    }
    out
}
