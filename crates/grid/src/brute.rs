//! Brute-force closest hit over every triangle: the reference every grid is tested against.
//! Same triangle test, same tie-break, so a correct grid reproduces its hits bit for bit.

use glam::Vec3;
use gridrt_scene::{Hit, Ray};

use crate::ray::PreparedRay;
use crate::stats::RayStats;
use crate::triangle::{closer, intersect};

/// Closest hit of `ray` among `tris` (t, then index), with stats (every triangle is a test).
pub fn trace(tris: &[[Vec3; 3]], ray: &Ray) -> (Hit, RayStats) {
    let Some(r) = PreparedRay::new(ray) else {
        return (Hit::MISS, RayStats::default());
    };
    let mut best = Hit::MISS;
    for (i, tri) in tris.iter().enumerate() {
        if let Some(h) = intersect(&r, tri)
            && closer(h.t, i as u32, best.t, best.triangle)
        {
            best = Hit { t: h.t, triangle: i as u32, u: h.u, v: h.v };
        }
    }
    (best, RayStats { cells: 0, tests: tris.len() as u32 })
}
