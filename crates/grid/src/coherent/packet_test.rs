//! One triangle against every active ray of a packet, eight rays at a time.
//!
//! The rays are grouped by the axis permutation of their watertight test (most packets have
//! one). For a group, the triangle's corners are read at the group's permutation and the f32
//! pre-filter of [`crate::triangle::certainly_outside`] runs for eight rays at once: eight-lane
//! arrays the compiler vectorizes, in versions for AVX2 (one 256-bit register), AVX and the
//! baseline (two SSE halves on x86-64; NEON or simd128 elsewhere), picked at run time by the
//! CPU's features (`multiversion`). Each lane does the scalar pre-filter's operations in the same
//! order, so it rejects exactly the rays the scalar pre-filter rejects. The rays it cannot reject take the
//! scalar [`crate::triangle::intersect_prefiltered`], so hits are those of single rays, bit for bit.

use glam::Vec3;
use gridrt_scene::Hit;

use super::frustum::{Lane, LineBounds, SliceWalk, TriangleBox, lines_interval};
use crate::ray::PreparedRay;
use crate::triangle::{
    RayLanes, certainly_outside, intersect_prefiltered, intersect8_prefiltered, keep_closer, permuted_corners, shear,
};

/// Rays per SIMD chunk.
pub const LANES: usize = 8;

/// Rays of a chunk the pre-filter keeps from which their exact tests run in lanes
/// ([`intersect8_prefiltered`]) rather than one by one.
pub const LANE_TESTS_FROM: u32 = 3;

/// Rays sharing one axis permutation: `start..start + len` of the gathered arrays (padded to
/// whole chunks of eight).
#[derive(Clone, Copy, Debug)]
struct Group {
    perm: [usize; 3],
    start: usize,
    len: usize,
}

/// The active rays of a packet, gathered by permutation into arrays of eight-ray chunks.
#[derive(Clone, Debug, Default)]
pub struct PacketRays {
    groups: Vec<Group>,
    /// Where each lane's ray is (`u32::MAX`: not gathered or removed).
    pos: Vec<u32>,
    /// Rays removed since the last gather.
    dead: usize,
    /// Lane index of each ray (`u32::MAX` in padding and for removed rays): its prepared ray,
    /// for the exact test, is the lane's (not copied).
    lane: Vec<u32>,
    /// The origin at the permutation (x, y, z) and the shear.
    ox: Vec<f32>,
    oy: Vec<f32>,
    oz: Vec<f32>,
    sx: Vec<f32>,
    sy: Vec<f32>,
    /// Per chunk of eight, the bounds of its rays' lines (a triangle whose box none of them
    /// passes through is not tested against the chunk).
    chunk_lines: Vec<ChunkLines>,
    /// Each active lane's permutation code while gathering.
    codes: Vec<u8>,
}

impl PacketRays {
    /// The rays of the `active` lanes (`lanes` many in the packet), by permutation.
    pub fn gather(&mut self, lanes: &[Lane], active: &[u32]) {
        // The permutation is fixed by the dominant axis kz and whether kx, ky are swapped.
        let code = |r: &PreparedRay| r.kz * 2 + (r.kx != (r.kz + 1) % 3) as usize;
        let ray = |i: u32| lanes[i as usize].ray.as_ref().expect("active lanes are valid");
        // A counting sort by permutation: each group's place, padded to whole chunks.
        let mut count = [0usize; 6];
        let mut perm = [[0usize; 3]; 6];
        self.codes.clear();
        for &i in active {
            let r = ray(i);
            let c = code(r);
            count[c] += 1;
            perm[c] = [r.kx, r.ky, r.kz];
            self.codes.push(c as u8);
        }
        self.groups.clear();
        let mut next = [0usize; 6];
        let mut total = 0;
        for c in (0..6).filter(|&c| count[c] > 0) {
            self.groups.push(Group { perm: perm[c], start: total, len: count[c] });
            next[c] = total;
            total += count[c].next_multiple_of(LANES);
        }
        self.lane.clear();
        self.lane.resize(total, u32::MAX);
        for v in [&mut self.ox, &mut self.oy, &mut self.oz, &mut self.sx, &mut self.sy] {
            v.clear();
            v.resize(total, 0.0);
        }
        self.pos.clear();
        self.pos.resize(lanes.len(), u32::MAX);
        self.dead = 0;
        for (&i, &c) in active.iter().zip(&self.codes) {
            let k = next[c as usize];
            next[c as usize] += 1;
            let r = ray(i);
            self.pos[i as usize] = k as u32;
            self.lane[k] = i;
            (self.ox[k], self.oy[k], self.oz[k]) = (r.org_k[0], r.org_k[1], r.org_k[2]);
            (self.sx[k], self.sy[k]) = (r.sx, r.sy);
        }
        // Padding lanes (lane `u32::MAX`) repeat their group's first ray: finite values, never
        // a hit recorded.
        for g in &self.groups {
            for k in g.start + g.len..g.start + g.len.next_multiple_of(LANES) {
                (self.ox[k], self.oy[k], self.oz[k]) = (self.ox[g.start], self.oy[g.start], self.oz[g.start]);
                (self.sx[k], self.sy[k]) = (self.sx[g.start], self.sy[g.start]);
            }
        }
        self.chunk_lines.clear();
    }

    /// Whether [`PacketRays::bound_chunks`] has run since the last gather.
    #[inline]
    pub fn chunks_bounded(&self) -> bool {
        !self.chunk_lines.is_empty()
    }

    /// The bounds of each chunk's lines (`lanes` of `walk`), for the tests that spare the
    /// chunks a triangle's box lies away from. Computed when a packet first checks its chunks
    /// (packets that test no triangle, or do not check, never need them).
    pub fn bound_chunks(&mut self, lanes: &[Lane], walk: &SliceWalk) {
        self.chunk_lines.clear();
        for (k, chunk) in self.lane.chunks(LANES).enumerate() {
            if k.is_multiple_of(LANES) {
                self.chunk_lines.push(ChunkLines::NONE);
            }
            let lines = walk.line_bounds(lanes, chunk.iter().copied().filter(|&i| i != u32::MAX));
            self.chunk_lines[k / LANES].set(k % LANES, &lines);
        }
    }

    /// Drops the ray of lane `i` (it is skipped from now on); returns the rays dropped since
    /// the last gather.
    #[inline]
    pub fn remove(&mut self, i: u32) -> usize {
        let k = self.pos[i as usize];
        if k != u32::MAX {
            self.lane[k as usize] = u32::MAX;
            self.pos[i as usize] = u32::MAX;
            self.dead += 1;
        }
        self.dead
    }

    /// Tests triangle `t` against every gathered ray, keeping each lane's closest hit in
    /// `best`; true when some lane's hit changed. With `t.cull`, each chunk whose lines all pass away from the triangle's box is spared
    /// (counted in `cull_stats`).
    #[inline]
    pub fn test(&self, lanes: &[Lane], t: &TriangleTest, best: &mut [Hit], cull_stats: &mut CullStats) -> bool {
        test_rays(self, lanes, t, best, cull_stats)
    }
}

/// Chunks of rays checked against triangles' boxes, and how many of them the checks spared.
#[derive(Clone, Copy, Debug, Default)]
pub struct CullStats {
    pub checked: u64,
    pub spared: u64,
}

/// A triangle a packet tests: its corners, its index and, when the packet checks its chunks
/// of rays against the triangle's box, the walk and the box.
#[derive(Clone, Copy, Debug)]
pub struct TriangleTest<'a> {
    pub tri: &'a [Vec3; 3],
    pub id: u32,
    pub cull: Option<(&'a SliceWalk, &'a TriangleBox)>,
}

/// [`PacketRays::test`], compiled for AVX2 and AVX besides the baseline and chosen at run time
/// by the CPU's features (`multiversion`). The pre-filter's eight lanes are plain arrays the
/// compiler vectorizes for each version: one AVX register, or two SSE halves. The operations and
/// their order are the same in every version (no FMA contraction), so every version rejects the
/// same rays.
#[allow(unsafe_code)] // the dispatch `multiversion` generates: a version runs only where its features are detected
#[multiversion::multiversion(targets("x86_64+avx2+fma", "x86_64+avx"))]
fn test_rays(
    rays: &PacketRays,
    lanes: &[Lane],
    t: &TriangleTest,
    best: &mut [Hit],
    cull_stats: &mut CullStats,
) -> bool {
    let TriangleTest { tri, id, cull } = *t;
    let mut changed = false;
    let mut live = u32::MAX;
    // The prepared ray at position `k` of the gathered arrays (none in padding or for a
    // removed ray; a valid lane always has its ray).
    let ray_at = |k: usize| lanes.get(rays.lane[k] as usize).and_then(|l| l.ray.as_ref());
    for g in &rays.groups {
        let corners = permuted_corners(tri, g.perm);
        for chunk in (g.start..g.start + g.len).step_by(LANES) {
            let k = chunk / LANES;
            if let Some((walk, b)) = cull {
                if k.is_multiple_of(LANES) {
                    live = rays.chunk_lines[k / LANES].meeting(walk.axis, walk.reference_plane(), b);
                }
                cull_stats.checked += 1;
                if live & (1 << (k % LANES)) == 0 {
                    cull_stats.spared += 1;
                    continue;
                }
            }
            let chunk_of = |v: &[f32]| -> Lanes { v[chunk..chunk + LANES].try_into().expect("eight lanes") };
            let o = [chunk_of(&rays.ox), chunk_of(&rays.oy), chunk_of(&rays.oz)];
            let shear = [chunk_of(&rays.sx), chunk_of(&rays.sy)];
            let mut keep = !certainly_outside8(&corners, &o, &shear) & 0xff;
            // Several rays kept: their exact tests in lanes (the rest of each ray read from its
            // lane; padding and removed rays keep placeholder values, and no hit is kept).
            if keep.count_ones() >= LANE_TESTS_FROM {
                let (mut sz, mut tmin, mut tmax) = ([1.0; LANES], [0.0; LANES], [0.0; LANES]);
                for l in 0..LANES {
                    if let Some(ray) = ray_at(chunk + l) {
                        (sz[l], tmin[l], tmax[l]) = (ray.sz, ray.tmin, ray.tmax);
                    }
                }
                let r = RayLanes { o, s: [shear[0], shear[1], sz], tmin, tmax };
                let (hits, hit) = intersect8_prefiltered(&corners, &r);
                keep &= hit;
                while keep != 0 {
                    let l = keep.trailing_zeros() as usize;
                    keep &= keep - 1;
                    if ray_at(chunk + l).is_some() {
                        changed |= keep_closer(&mut best[rays.lane[chunk + l] as usize], Some(hits[l]), id);
                    }
                }
                continue;
            }
            while keep != 0 {
                let k = chunk + keep.trailing_zeros() as usize;
                keep &= keep - 1;
                let Some(ray) = ray_at(k) else { continue };
                changed |= keep_closer(&mut best[rays.lane[k] as usize], intersect_prefiltered(ray, tri), id);
            }
        }
    }
    changed
}

/// Eight rays' values of one quantity.
type Lanes = [f32; LANES];

/// [`crate::triangle::intersect`]'s shear and [`crate::triangle::certainly_outside`] for eight
/// rays (origins `o`, shear `s`) against one triangle's corners at their permutation: a bit per
/// ray whose origin is certainly outside. Each lane calls the scalar rule; the loop vectorizes.
#[inline(always)]
fn certainly_outside8(corners: &[[f32; 3]; 3], o: &[Lanes; 3], s: &[Lanes; 2]) -> u32 {
    let mut mask = 0u32;
    for l in 0..LANES {
        let sheared = |c: &[f32; 3]| {
            let [x, y, _] = shear(*c, [o[0][l], o[1][l], o[2][l]], [s[0][l], s[1][l]]);
            [x, y]
        };
        let outside = certainly_outside(sheared(&corners[0]), sheared(&corners[1]), sheared(&corners[2]));
        mask |= u32::from(outside) << l;
    }
    mask
}

/// The line bounds of eight chunks (a chunk's lane of each array), so that a triangle is
/// checked against all eight at once ([`ChunkLines::meeting`]).
#[derive(Clone, Copy, Debug)]
struct ChunkLines {
    /// Per axis other than the walk axis: the intercepts' and slopes' bounds.
    c_lo: [[f64; LANES]; 2],
    c_hi: [[f64; LANES]; 2],
    slope_lo: [[f64; LANES]; 2],
    slope_hi: [[f64; LANES]; 2],
}

impl ChunkLines {
    /// No lines: every triangle misses them (an empty interval, with slopes that cannot make
    /// a NaN).
    const NONE: ChunkLines = ChunkLines {
        c_lo: [[f64::INFINITY; LANES]; 2],
        c_hi: [[f64::NEG_INFINITY; LANES]; 2],
        slope_lo: [[0.0; LANES]; 2],
        slope_hi: [[0.0; LANES]; 2],
    };

    fn set(&mut self, l: usize, lines: &LineBounds) {
        let b = &lines.0;
        for n in 0..2 {
            // A chunk without a ray keeps `NONE`'s values.
            if b.c_lo[n] <= b.c_hi[n] {
                (self.c_lo[n][l], self.c_hi[n][l]) = (b.c_lo[n], b.c_hi[n]);
                (self.slope_lo[n][l], self.slope_hi[n][l]) = (b.slope_lo[n], b.slope_hi[n]);
            }
        }
    }

    /// A bit per chunk some of whose lines pass through the triangle box `b` (walk axis `a`,
    /// intercepts at plane `s_ref`): then, and only then, can one of its rays hit the triangle
    /// (a hit lies in the box, and a ray's line passes within the slice margin of it). Each
    /// lane is the scalar rule [`lines_interval`] over the box's extent on the walk axis.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // `l` is the lane of every array
    fn meeting(&self, a: usize, s_ref: f64, b: &TriangleBox) -> u32 {
        let d = (b.lo[a] - s_ref, b.hi[a] - s_ref);
        let mut miss = [false; LANES];
        for (n, u) in [(a + 1) % 3, (a + 2) % 3].into_iter().enumerate() {
            for l in 0..LANES {
                let c = (self.c_lo[n][l], self.c_hi[n][l]);
                let (lo, hi) = lines_interval(c, (self.slope_lo[n][l], self.slope_hi[n][l]), d);
                miss[l] |= (hi < b.lo[u]) | (lo > b.hi[u]);
            }
        }
        let mut live = 0u32;
        for (l, &x) in miss.iter().enumerate() {
            live |= u32::from(!x) << l;
        }
        live
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::GridGeometry;
    use gridrt_scene::rng::Rng;
    use gridrt_scene::{Aabb, Ray};

    /// The scalar rule for one chunk: whether none of its lines passes through `b`.
    fn lines_miss(walk: &SliceWalk, lines: &LineBounds, b: &TriangleBox) -> bool {
        let (a, l) = (walk.axis, &lines.0);
        let d = (b.lo[a] - walk.reference_plane(), b.hi[a] - walk.reference_plane());
        [(a + 1) % 3, (a + 2) % 3].into_iter().enumerate().any(|(n, u)| {
            let (lo, hi) = lines_interval((l.c_lo[n], l.c_hi[n]), (l.slope_lo[n], l.slope_hi[n]), d);
            hi < b.lo[u] || lo > b.hi[u]
        })
    }

    /// Packets of rays (from a common origin, towards a common end, or scattered within a
    /// cone) against small and large triangles near them: every ray that hits a triangle is in
    /// a chunk the box check keeps, the eight-lane check equals the scalar one, and the check
    /// spares chunks (it is not vacuous).
    #[test]
    fn the_chunk_check_keeps_every_ray_that_hits() {
        let mut rng = Rng::new(19);
        let bounds = Aabb { min: Vec3::new(-2.0, -1.0, -3.0), max: Vec3::new(5.0, 4.0, 2.0) };
        let (mut kept_hits, mut spared) = (0, 0);
        for case in 0..300 {
            let geom = GridGeometry::new(
                &bounds,
                [3 + rng.below(40) as u32, 3 + rng.below(40) as u32, 3 + rng.below(40) as u32],
            );
            let inside = |rng: &mut Rng| Vec3::new(rng.range(-2.0, 5.0), rng.range(-1.0, 4.0), rng.range(-3.0, 2.0));
            let (eye, target) = (inside(&mut rng) * 3.0, inside(&mut rng));
            let spread = rng.range(0.001, 0.3);
            let rays: Vec<Ray> = (0..64)
                .map(|i| {
                    let (dx, dy) = ((i % 8) as f32 - 3.5, (i / 8) as f32 - 3.5);
                    let d = (target - eye).normalize() + spread * Vec3::new(dx, dy, 0.3 * dx - 0.2 * dy) / 8.0;
                    match case % 3 {
                        // A common origin (a camera tile).
                        0 => Ray::new(eye, d, 0.0, f32::INFINITY),
                        // A common end (shadow rays towards a light at `eye`).
                        1 => {
                            let o = eye + d * rng.range(2.0, 9.0);
                            Ray::new(o, eye - o, 1e-4, 1.0)
                        }
                        // Nearby origins.
                        _ => Ray::new(eye + Vec3::splat(rng.range(-0.2, 0.2)), d, 0.0, f32::INFINITY),
                    }
                })
                .collect();
            let (mut lanes, mut active) = (Vec::new(), Vec::new());
            let Some(walk) = SliceWalk::new(&geom, &rays, &mut lanes, &mut active) else { continue };
            let mut packet = PacketRays::default();
            packet.gather(&lanes, &active);
            packet.bound_chunks(&lanes, &walk);
            for _ in 0..40 {
                // A triangle around a point of one of the rays, of a random size.
                let r = &rays[rng.below(64) as usize];
                let p = r.at(rng.range(0.5, 1.0).min(r.tmax));
                let size = [0.001, 0.05, 0.5, 3.0][rng.below(4) as usize];
                let tri = [0; 3].map(|_| p + rng.unit_vector() * size);
                let b = TriangleBox::of(&geom, &tri);
                for (block, lines) in packet.chunk_lines.iter().enumerate() {
                    let live = lines.meeting(walk.axis, walk.reference_plane(), &b);
                    for l in 0..LANES {
                        let k = block * LANES + l;
                        let Some(chunk) = packet.lane.get(k * LANES..(k + 1) * LANES) else { continue };
                        let scalar = walk.line_bounds(&lanes, chunk.iter().copied().filter(|&i| i != u32::MAX));
                        let scalar_live = chunk.iter().any(|&i| i != u32::MAX) && !lines_miss(&walk, &scalar, &b);
                        assert_eq!(live & (1 << l) != 0, scalar_live, "case {case}: lanes and scalar disagree");
                        for &i in chunk.iter().filter(|&&i| i != u32::MAX) {
                            let ray = lanes[i as usize].ray.expect("gathered lanes are valid");
                            let hit = crate::triangle::intersect(&ray, &tri)
                                .is_some_and(|h| h.t >= rays[i as usize].tmin && h.t <= rays[i as usize].tmax);
                            if hit {
                                assert!(scalar_live, "case {case}: a chunk with a hit was spared");
                                kept_hits += 1;
                            }
                        }
                        spared += usize::from(!scalar_live);
                    }
                }
            }
        }
        assert!(
            kept_hits > 1000 && spared > 1000,
            "the cases exercise the check: {kept_hits} hits kept, {spared} chunks spared"
        );
    }
}
