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
//!   Its box entries are clamped to t ≥ 1e-4 instead, so a hit closer than that is invisible to
//!   it (random rays start inside scanned models, a few per 100k); the bench counts those rays
//!   apart instead of as disagreements.
//!
//! With the `embree` feature (Debian's libembree-dev 3.13 through the `embree3` crate), Embree
//! joins as two rows: single rays (`rtcIntersect1`) and 8-ray packets (`rtcIntersect8`), both on
//! its default medium-quality build with the robust (watertight) flag and its own triangle test,
//! so its hits are compared like the "own test" row. Its memory is what its memory monitor saw
//! allocated by the build, less the vertex and index buffers.

use std::time::Duration;

use bvh::aabb::{Aabb as BvhAabb, Bounded};
use bvh::bounding_hierarchy::{BHShape, BoundingHierarchy};
use bvh::bvh::{Bvh, BvhNode};
use glam::{Vec3, Vec3A};
use gridrt_grid::Query;
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
    /// Embree 3 (robust scene, medium build), one ray at a time.
    #[cfg(feature = "embree")]
    Embree,
    /// Embree 3, the same scene, rays in packets of 8.
    #[cfg(feature = "embree")]
    EmbreePacket8,
}

impl PeerKind {
    pub const ALL: &[PeerKind] = &[
        PeerKind::Bvh,
        PeerKind::ObvhsFastest,
        PeerKind::ObvhsMedium,
        PeerKind::ObvhsCwbvh,
        PeerKind::ObvhsCwbvhOwnTest,
        #[cfg(feature = "embree")]
        PeerKind::Embree,
        #[cfg(feature = "embree")]
        PeerKind::EmbreePacket8,
    ];

    pub fn name(self) -> &'static str {
        match self {
            PeerKind::Bvh => "bvh (build_par)",
            PeerKind::ObvhsFastest => "obvhs BVH2 fastest",
            PeerKind::ObvhsMedium => "obvhs BVH2 medium",
            PeerKind::ObvhsCwbvh => "obvhs CWBVH medium",
            PeerKind::ObvhsCwbvhOwnTest => "obvhs CWBVH medium, own test",
            #[cfg(feature = "embree")]
            PeerKind::Embree => "Embree 3 (own test)",
            #[cfg(feature = "embree")]
            PeerKind::EmbreePacket8 => "Embree 3 packets of 8 (own test)",
        }
    }

    /// Whether the peer uses the grids' triangle test (its hits must then equal the grids').
    pub fn shared_test(self) -> bool {
        match self {
            PeerKind::ObvhsCwbvhOwnTest => false,
            #[cfg(feature = "embree")]
            PeerKind::Embree | PeerKind::EmbreePacket8 => false,
            _ => true,
        }
    }

    /// obvhs' CWBVH clamps every box entry to t ≥ 1e-4 (`EPSILON` in its node test; it
    /// ignores `ray.tmin`), so it cannot see hits closer than that (PEERS.md).
    pub fn blind_distance(self) -> Option<f32> {
        matches!(self, PeerKind::ObvhsCwbvh | PeerKind::ObvhsCwbvhOwnTest).then_some(1e-4)
    }

    /// Whether the library's build runs on all threads (`bvh`'s `build_par`; obvhs' `parallel`
    /// feature is off: on 2 cores its threads only add contention; Embree builds on its own
    /// threads).
    pub fn parallel_build(self) -> bool {
        match self {
            PeerKind::Bvh => true,
            #[cfg(feature = "embree")]
            PeerKind::Embree | PeerKind::EmbreePacket8 => true,
            _ => false,
        }
    }
}

/// A triangle's box in `bvh`'s type.
fn shape_bounds(t: &[Vec3; 3]) -> BvhAabb<f32, 3> {
    let lo = t[0].min(t[1]).min(t[2]);
    let hi = t[0].max(t[1]).max(t[2]);
    BvhAabb::with_bounds(lo.to_array().into(), hi.to_array().into())
}

/// A triangle as a `bvh` shape: its index and the node the builder assigns.
#[derive(Clone, Copy, Debug)]
pub struct Shape {
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
    Bvh {
        bvh: Bvh<f32, 3>,
        /// The triangles' boxes, each with its leaf (kept for `update_shapes`).
        shapes: Vec<Shape>,
    },
    Bvh2(Bvh2),
    Cw {
        bvh: CwBvh,
        tris: Option<Vec<Triangle>>,
    },
    #[cfg(feature = "embree")]
    Embree(embree::EmbreeScene),
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
            let mut shapes: Vec<Shape> = tris.iter().map(|t| Shape { bounds: shape_bounds(t), node: 0 }).collect();
            let bvh = Bvh::build_par(&mut shapes);
            PeerBvh::Bvh { bvh, shapes }
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
        #[cfg(feature = "embree")]
        PeerKind::Embree | PeerKind::EmbreePacket8 => {
            PeerBvh::Embree(embree::EmbreeScene::build(tris, kind == PeerKind::EmbreePacket8))
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
                v(bvh.nodes.len(), size_of::<BvhNode<f32, 3>>()) + v(shapes.len(), size_of::<Shape>())
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
            #[cfg(feature = "embree")]
            PeerBvh::Embree(e) => e.memory_bytes,
        }
    }

    /// Updates the tree to its triangles moved in place (same order), with the library's own
    /// update: obvhs BVH2 refits (every leaf's box from its triangles, then the inner nodes
    /// bottom-up, `Bvh2::refit_all`: the topology stays, so quality decays as triangles move);
    /// `bvh` re-inserts every triangle whose box changed (`Bvh::update_shapes`: each is removed
    /// and added again, descending the tree). `false` for the other peers.
    pub fn refit(&mut self, tris: &[[Vec3; 3]]) -> bool {
        if let PeerBvh::Bvh { bvh, shapes } = self {
            let changed: Vec<usize> = tris
                .iter()
                .zip(shapes.iter_mut())
                .enumerate()
                .filter_map(|(i, (t, s))| {
                    let b = shape_bounds(t);
                    (b != s.bounds).then(|| s.bounds = b).map(|()| i)
                })
                .collect();
            bvh.update_shapes(&changed, shapes);
            return true;
        }
        let PeerBvh::Bvh2(b) = self else { return false };
        let Bvh2 { nodes, primitive_indices, .. } = b;
        for node in nodes.iter_mut().filter(|n| n.is_leaf()) {
            let mut bb = obvhs::aabb::Aabb::empty();
            for &p in &primitive_indices[node.first_index as usize..(node.first_index + node.prim_count) as usize] {
                for v in tris[p as usize] {
                    bb.extend(v.into());
                }
            }
            node.set_aabb(bb);
        }
        b.refit_all();
        true
    }

    /// The closest hits of `rays` (or any hits, by `query`), on all threads. Embree answers
    /// occlusion queries with closest hits (right, not faster: its occlusion call is not part of
    /// any measurement here).
    pub fn trace_batch(&self, tris: &[[Vec3; 3]], rays: &[Ray], query: Query) -> Vec<Hit> {
        use rayon::prelude::*;
        #[cfg(feature = "embree")]
        if let PeerBvh::Embree(e) = self {
            return rays.par_chunks(1024).flat_map_iter(|c| e.trace(c)).collect();
        }
        rays.par_chunks(1024)
            .flat_map_iter(|c| c.iter().map(|r| self.trace(tris, r, query)).collect::<Vec<_>>())
            .collect()
    }

    /// The closest hit of `ray` (a miss for rays no triangle can be hit by); for
    /// [`Query::Any`] the first hit found, through each library's early-exit traversal
    /// (obvhs' `ray_traverse_miss`; the `bvh` loop returns at its first hit).
    pub fn trace(&self, tris: &[[Vec3; 3]], ray: &Ray, query: Query) -> Hit {
        let Some(prepared) = PreparedRay::new(ray) else { return Hit::MISS };
        let mut best = Closest { ray: prepared, hit: Hit::MISS };
        let any = query == Query::Any;
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
                            if any && best.hit.is_hit() {
                                return best.hit;
                            }
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
                if any {
                    b.ray_traverse_miss(r, |r, slot| best.test(tris, b.primitive_indices[slot], r.tmax));
                } else {
                    let mut rh = RayHit::none();
                    b.ray_traverse(r, &mut rh, |r, slot| best.test(tris, b.primitive_indices[slot], r.tmax));
                }
            }
            PeerBvh::Cw { bvh, tris: None } => {
                let r = obvhs::ray::Ray::new(Vec3A::from(ray.o()), Vec3A::from(ray.d()), ray.tmin, ray.tmax);
                if any {
                    bvh.ray_traverse_miss(r, |r, slot| best.test(tris, bvh.primitive_indices[slot], r.tmax));
                } else {
                    let mut rh = RayHit::none();
                    bvh.ray_traverse(r, &mut rh, |r, slot| best.test(tris, bvh.primitive_indices[slot], r.tmax));
                }
            }
            PeerBvh::Cw { bvh, tris: Some(ot) } => {
                let r = obvhs::ray::Ray::new(Vec3A::from(ray.o()), Vec3A::from(ray.d()), ray.tmin, ray.tmax);
                if any {
                    let mut found = Hit::MISS;
                    bvh.ray_traverse_miss(r, |r, slot| {
                        let triangle = bvh.primitive_indices[slot];
                        let t = ot[triangle as usize].intersect(r);
                        if t < r.tmax {
                            found = Hit { t, triangle, u: 0.0, v: 0.0 };
                        }
                        t
                    });
                    return found;
                }
                let mut rh = RayHit::none();
                if bvh.ray_traverse(r, &mut rh, |r, slot| ot[bvh.primitive_indices[slot] as usize].intersect(r)) {
                    let triangle = bvh.primitive_indices[rh.primitive_id as usize];
                    return Hit { t: rh.t, triangle, u: 0.0, v: 0.0 };
                }
                return Hit::MISS;
            }
            #[cfg(feature = "embree")]
            PeerBvh::Embree(e) => return e.trace(std::slice::from_ref(ray))[0],
        }
        best.hit
    }
}

#[cfg(feature = "embree")]
mod embree {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicI64, Ordering};

    use embree3::{
        BufferUsage, BuildQuality, Device, Format, GeometryKind, Hit8, IntersectContext, Ray8, RayHit, RayHit8,
        SceneFlags, ValidMask, ValidMaskN,
    };
    use glam::Vec3;
    use gridrt_grid::ray::PreparedRay;
    use gridrt_scene::{Hit, Ray};

    /// A committed Embree scene over the triangles (unshared vertices, one geometry).
    pub struct EmbreeScene {
        scene: embree3::Scene<'static>,
        /// Trace in packets of 8.
        packets: bool,
        pub memory_bytes: u64,
    }

    impl EmbreeScene {
        pub fn build(tris: &[[Vec3; 3]], packets: bool) -> EmbreeScene {
            let device = Device::new().expect("Embree device");
            let allocated = Arc::new(AtomicI64::new(0));
            let counter = allocated.clone();
            device.set_memory_monitor_function(move |bytes, _post| {
                counter.fetch_add(bytes as i64, Ordering::Relaxed);
                true
            });
            let mut scene = device.create_scene().expect("Embree scene");
            scene.set_flags(SceneFlags::ROBUST);
            scene.set_build_quality(BuildQuality::MEDIUM);
            let n = tris.len().max(1);
            let mut geom = device.create_geometry(GeometryKind::TRIANGLE).expect("Embree geometry");
            let mut vb = geom
                .set_new_buffer::<[f32; 3]>(BufferUsage::VERTEX, 0, Format::FLOAT3, 12, 3 * n)
                .expect("Embree vertex buffer");
            // Straight into Embree's buffer (the build is timed).
            for (dst, v) in vb.iter_mut().zip(tris.iter().flatten()) {
                *dst = v.to_array();
            }
            let mut ib = geom
                .set_new_buffer::<[u32; 3]>(BufferUsage::INDEX, 0, Format::UINT3, 12, n)
                .expect("Embree index buffer");
            for (i, t) in ib.iter_mut().enumerate().take(tris.len()) {
                let k = 3 * i as u32;
                *t = [k, k + 1, k + 2];
            }
            let buffers = allocated.load(Ordering::Relaxed);
            let geom = geom.commit();
            scene.attach_geometry(&geom);
            scene.commit();
            let memory_bytes = (allocated.load(Ordering::Relaxed) - buffers).max(0) as u64;
            device.unset_memory_monitor_function();
            EmbreeScene { scene, packets, memory_bytes }
        }

        /// The closest hits of `rays` (rays no triangle can be hit by miss, as for the grids).
        pub fn trace(&self, rays: &[Ray]) -> Vec<Hit> {
            let to_hit = |t: f32, prim: u32, u: f32, v: f32| {
                if prim == embree3::INVALID_ID { Hit::MISS } else { Hit { t, triangle: prim, u, v } }
            };
            if !self.packets {
                let mut ctx = IntersectContext::incoherent();
                return rays
                    .iter()
                    .map(|r| {
                        if PreparedRay::new(r).is_none() {
                            return Hit::MISS;
                        }
                        let mut rh = RayHit::from(embree3::Ray::segment(r.o().into(), r.d().into(), r.tmin, r.tmax));
                        self.scene.intersect(&mut ctx, &mut rh);
                        to_hit(rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v)
                    })
                    .collect();
            }
            /// rtcIntersect8 reads its valid mask with 32-byte loads; `ValidMaskN` is only
            /// 16-byte aligned.
            #[repr(C, align(32))]
            struct Mask8(ValidMaskN<8>);
            let mut ctx = IntersectContext::coherent();
            let mut out = Vec::with_capacity(rays.len());
            for group in rays.chunks(8) {
                let mut mask = Mask8(ValidMaskN::<8>::all_active());
                let valid = &mut mask.0;
                let (mut org, mut dir, mut tnear, mut tfar) =
                    ([[0.0; 3]; 8], [[0.0, 0.0, 1.0]; 8], [0.0; 8], [-1.0; 8]);
                for (i, r) in group.iter().enumerate() {
                    (org[i], dir[i], tnear[i], tfar[i]) = (r.o().into(), r.d().into(), r.tmin, r.tmax);
                }
                for i in 0..8 {
                    if i >= group.len() || PreparedRay::new(&group[i]).is_none() {
                        valid.lanes_mut()[i] = ValidMask::Invalid;
                    }
                }
                let mut rh = RayHit8 { ray: Ray8::segment(org, dir, tnear, tfar), hit: Hit8::new() };
                self.scene.intersect8(&mut ctx, &mut rh, valid);
                for i in 0..group.len() {
                    out.push(if valid.lanes_mut()[i] == ValidMask::Invalid {
                        Hit::MISS
                    } else {
                        to_hit(rh.ray.tfar[i], rh.hit.primID[i], rh.hit.u[i], rh.hit.v[i])
                    });
                }
            }
            out
        }
    }
}
