//! The BVHs users would pick instead of a grid, built and traced the way `gridrt bench`
//! compares them: the `bvh` crate (svenstaro) and `obvhs`, on the same triangles and rays.
//!
//! Every peer intersects triangles with the grids' own watertight test and the same
//! deterministic tie-break (smaller t, then smaller index), so a peer's answer must equal the
//! grids' answer bit for bit and the comparison measures the acceleration structure alone. The
//! bench checks that agreement on every ray and reports it. One extra row runs obvhs' CWBVH
//! with obvhs' own f32 triangle test, the way its examples use it, to show what the shared
//! test costs it.
//!
//! Pitfalls of benchmarking BVH libraries, handled here:
//! - `bvh` has no closest-hit traversal (`traverse` returns every shape whose box is hit, its
//!   iterator has a 32-entry stack and its ray/triangle test culls back faces), so it is
//!   traversed by an ordered closest-hit loop over its public `nodes`: nearer child first,
//!   children beyond the current closest hit skipped.
//! - obvhs' callbacks receive a slot in `primitive_indices`, not the triangle id: remapped.
//! - obvhs' CWBVH ignores `ray.tmin` in its box tests; the shared triangle test enforces it.

use std::time::Duration;

use bvh::aabb::{Aabb as BvhAabb, Bounded};
use bvh::bounding_hierarchy::{BHShape, BoundingHierarchy};
use bvh::bvh::{Bvh, BvhNode};
use glam::{Vec3, Vec3A};
use gridrt_grid::ray::PreparedRay;
use gridrt_grid::triangle::{closer, intersect};
use gridrt_scene::{Hit, Ray};
use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::RayHit;
use obvhs::triangle::Triangle;

/// The peer configurations `gridrt bench` measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PeerKind {
    /// `bvh` 0.13, `build_par` (SAH, rayon), ordered closest-hit loop over its nodes.
    Bvh,
    /// obvhs 0.4 BVH2 with its fastest build preset (PLOC, no reinsertion, 1 triangle a leaf).
    ObvhsFastest,
    /// obvhs BVH2, `medium_build` (its traversal-quality preset for BVH2).
    ObvhsMedium,
    /// obvhs CWBVH (8-wide, compressed), `medium_build`: its fastest CPU traversal.
    ObvhsCwbvh,
    /// The same CWBVH traced with obvhs' own f32 triangle test (not watertight).
    ObvhsCwbvhOwnTest,
}

impl PeerKind {
    pub const ALL: [PeerKind; 5] = [
        PeerKind::Bvh,
        PeerKind::ObvhsFastest,
        PeerKind::ObvhsMedium,
        PeerKind::ObvhsCwbvh,
        PeerKind::ObvhsCwbvhOwnTest,
    ];

    pub fn name(self) -> &'static str {
        match self {
            PeerKind::Bvh => "bvh (build_par)",
            PeerKind::ObvhsFastest => "obvhs BVH2 fastest",
            PeerKind::ObvhsMedium => "obvhs BVH2 medium",
            PeerKind::ObvhsCwbvh => "obvhs CWBVH medium",
            PeerKind::ObvhsCwbvhOwnTest => "obvhs CWBVH medium, own test",
        }
    }

    /// Whether the peer uses the grids' triangle test (its hits must then equal the grids').
    pub fn shared_test(self) -> bool {
        self != PeerKind::ObvhsCwbvhOwnTest
    }

    /// Whether the library's build runs on all threads (`bvh`'s `build_par`; obvhs' `parallel`
    /// feature is off: on 2 cores its threads only add contention).
    pub fn parallel_build(self) -> bool {
        self == PeerKind::Bvh
    }
}

/// A triangle as a `bvh` shape: its index and the node the builder assigns.
#[derive(Clone, Copy, Debug)]
struct Shape {
    bounds: BvhAabb<f32, 3>,
    node: usize,
}

impl Bounded<f32, 3> for Shape {
    fn aabb(&self) -> BvhAabb<f32, 3> {
        self.bounds
    }
}

impl BHShape<f32, 3> for Shape {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}

/// A built peer structure.
pub enum PeerBvh {
    Bvh { bvh: Bvh<f32, 3>, shapes: usize },
    Bvh2(Bvh2),
    Cw { bvh: CwBvh, tris: Option<Vec<Triangle>> },
}

impl std::fmt::Debug for PeerBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PeerBvh({} bytes)", self.memory_bytes())
    }
}

fn obvhs_tris(tris: &[[Vec3; 3]]) -> Vec<Triangle> {
    tris.iter().map(|t| Triangle { v0: t[0].into(), v1: t[1].into(), v2: t[2].into() }).collect()
}

/// Builds `kind` over `tris` (the timed part: input conversion included, as a user pays it).
pub fn build(kind: PeerKind, tris: &[[Vec3; 3]]) -> PeerBvh {
    let mut core = Duration::default();
    match kind {
        PeerKind::Bvh => {
            let mut shapes: Vec<Shape> = tris
                .iter()
                .map(|t| {
                    let lo = t[0].min(t[1]).min(t[2]);
                    let hi = t[0].max(t[1]).max(t[2]);
                    Shape { bounds: BvhAabb::with_bounds(lo.to_array().into(), hi.to_array().into()), node: 0 }
                })
                .collect();
            let bvh = Bvh::build_par(&mut shapes);
            PeerBvh::Bvh { bvh, shapes: shapes.len() }
        }
        PeerKind::ObvhsFastest | PeerKind::ObvhsMedium => {
            let params = if kind == PeerKind::ObvhsFastest {
                BvhBuildParams::fastest_build()
            } else {
                BvhBuildParams::medium_build()
            };
            PeerBvh::Bvh2(obvhs::bvh2::builder::build_bvh2_from_tris(&obvhs_tris(tris), params, &mut core))
        }
        PeerKind::ObvhsCwbvh | PeerKind::ObvhsCwbvhOwnTest => {
            let ot = obvhs_tris(tris);
            let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(&ot, BvhBuildParams::medium_build(), &mut core);
            PeerBvh::Cw { bvh, tris: (kind == PeerKind::ObvhsCwbvhOwnTest).then_some(ot) }
        }
    }
}

/// The closest hit so far, in the grids' order (smaller t, then smaller triangle index).
struct Closest {
    ray: PreparedRay,
    hit: Hit,
}

impl Closest {
    /// Tests triangle `i` with the ray's interval capped at `tmax` (the traversal's current
    /// closest t; the interval is closed, so an equal-t hit with a smaller index still wins).
    #[inline]
    fn test(&mut self, tris: &[[Vec3; 3]], i: u32, tmax: f32) -> f32 {
        let mut r = self.ray;
        r.tmax = r.tmax.min(tmax);
        match intersect(&r, &tris[i as usize]) {
            Some(h) if closer(h.t, i, self.hit.t, self.hit.triangle) => {
                self.hit = Hit { t: h.t, triangle: i, u: h.u, v: h.v };
                h.t
            }
            _ => f32::INFINITY,
        }
    }
}

/// Slab test: the entry distance of `ray` into the box, or `None` when it misses within
/// `[tmin, tmax]`.
#[inline]
fn slab(org: Vec3, inv: Vec3, lo: Vec3, hi: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
    let a = (lo - org) * inv;
    let b = (hi - org) * inv;
    // NaN (0 · ∞ on a face plane) falls out of min/max towards the other operand.
    // A hit's t comes from the triangle test and a box's from the slabs: the two round
    // differently, and on Sponza a hit sat 1e-5 (relative) before its box's computed entry, so
    // the loop skipped it. Boxes are therefore widened by 1e-4 relative on both ends: a few
    // extra nodes, and the closest hit is never culled.
    const SLACK: f32 = 1e-4;
    let near = a.min(b).max_element().max(tmin);
    let far = a.max(b).min_element();
    let (near, far) = (near - SLACK * near.abs(), (far + SLACK * far.abs()).min(tmax));
    (near <= far).then_some(near.max(tmin))
}

fn bvh_box(b: &BvhAabb<f32, 3>) -> (Vec3, Vec3) {
    (Vec3::new(b.min[0], b.min[1], b.min[2]), Vec3::new(b.max[0], b.max[1], b.max[2]))
}

impl PeerBvh {
    /// Bytes of the acceleration structure (nodes and index arrays; triangles not counted, as
    /// for the grids).
    pub fn memory_bytes(&self) -> u64 {
        let v = |len: usize, size: usize| (len * size) as u64;
        match self {
            PeerBvh::Bvh { bvh, shapes } => {
                v(bvh.nodes.len(), size_of::<BvhNode<f32, 3>>()) + v(*shapes, size_of::<Shape>())
            }
            PeerBvh::Bvh2(b) => {
                v(b.nodes.len(), size_of::<obvhs::bvh2::node::Bvh2Node>())
                    + v(b.primitive_indices.len() + b.primitives_to_nodes.len() + b.parents.len(), 4)
            }
            PeerBvh::Cw { bvh, tris } => {
                v(bvh.nodes.len(), size_of::<obvhs::cwbvh::node::CwBvhNode>())
                    + v(bvh.primitive_indices.len(), 4)
                    + tris.as_ref().map_or(0, |t| v(t.len(), size_of::<Triangle>()))
            }
        }
    }

    /// The closest hit of `ray` (a miss for rays no triangle can be hit by).
    pub fn trace(&self, tris: &[[Vec3; 3]], ray: &Ray) -> Hit {
        let Some(prepared) = PreparedRay::new(ray) else { return Hit::MISS };
        let mut best = Closest { ray: prepared, hit: Hit::MISS };
        match self {
            PeerBvh::Bvh { bvh, .. } => {
                if bvh.nodes.is_empty() {
                    return Hit::MISS;
                }
                let org = ray.o();
                let inv = ray.d().recip();
                let mut stack: Vec<(usize, f32)> = Vec::with_capacity(64);
                stack.push((0, ray.tmin));
                while let Some((node, entry)) = stack.pop() {
                    if entry > best.hit.t.min(ray.tmax) {
                        continue;
                    }
                    match &bvh.nodes[node] {
                        BvhNode::Leaf { shape_index, .. } => {
                            best.test(tris, *shape_index as u32, f32::INFINITY);
                        }
                        BvhNode::Node { child_l_index, child_l_aabb, child_r_index, child_r_aabb, .. } => {
                            let tmax = best.hit.t.min(ray.tmax);
                            let (ll, lh) = bvh_box(child_l_aabb);
                            let (rl, rh) = bvh_box(child_r_aabb);
                            let l = slab(org, inv, ll, lh, ray.tmin, tmax);
                            let r = slab(org, inv, rl, rh, ray.tmin, tmax);
                            // Push the farther child first so the nearer one pops next.
                            match (l, r) {
                                (Some(tl), Some(tr)) if tl <= tr => {
                                    stack.push((*child_r_index, tr));
                                    stack.push((*child_l_index, tl));
                                }
                                (Some(tl), Some(tr)) => {
                                    stack.push((*child_l_index, tl));
                                    stack.push((*child_r_index, tr));
                                }
                                (Some(tl), None) => stack.push((*child_l_index, tl)),
                                (None, Some(tr)) => stack.push((*child_r_index, tr)),
                                (None, None) => {}
                            }
                        }
                    }
                }
            }
            PeerBvh::Bvh2(b) => {
                let r = obvhs::ray::Ray::new(Vec3A::from(ray.o()), Vec3A::from(ray.d()), ray.tmin, ray.tmax);
                let mut rh = RayHit::none();
                b.ray_traverse(r, &mut rh, |r, slot| best.test(tris, b.primitive_indices[slot], r.tmax));
            }
            PeerBvh::Cw { bvh, tris: None } => {
                let r = obvhs::ray::Ray::new(Vec3A::from(ray.o()), Vec3A::from(ray.d()), ray.tmin, ray.tmax);
                let mut rh = RayHit::none();
                bvh.ray_traverse(r, &mut rh, |r, slot| best.test(tris, bvh.primitive_indices[slot], r.tmax));
            }
            PeerBvh::Cw { bvh, tris: Some(ot) } => {
                let r = obvhs::ray::Ray::new(Vec3A::from(ray.o()), Vec3A::from(ray.d()), ray.tmin, ray.tmax);
                let mut rh = RayHit::none();
                if bvh.ray_traverse(r, &mut rh, |r, slot| ot[bvh.primitive_indices[slot] as usize].intersect(r)) {
                    let triangle = bvh.primitive_indices[rh.primitive_id as usize];
                    return Hit { t: rh.t, triangle, u: 0.0, v: 0.0 };
                }
                return Hit::MISS;
            }
        }
        best.hit
    }
}
