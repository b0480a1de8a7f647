//! Builds a [`Rig`] while the loader walks the document: node rest transforms, the visits and
//! instances in triangle order, each primitive's morph deltas and joint influences, then the
//! skins and clips. Their shape was validated by [`crate::animation_data`] and their counts by
//! [`crate::load_budget`]; the values are checked here, where each is decoded once (times
//! finite and strictly increasing, finite outputs, inverse bind matrices and morph deltas,
//! joint indices inside every skin that uses the mesh), as is what only the walk can see (a
//! skinned primitive without influences, a joint outside the scene whose ancestry does not end).

use glam::{DMat4, DQuat, Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::Property;

use super::{Channel, Clip, Influences, Instance, NodeRest, Primitive, Rig, Skin, Target, Trs, Visit};
use crate::accessor::{AccessorFault, read_components};
use crate::animation_data::mesh_targets;
use crate::error::{PrimitiveRef, SceneError};
use crate::gltf_load::MAX_NODE_DEPTH;
use crate::pose::sampler::Sampler;

const NO_VISIT: u32 = u32::MAX;

pub(crate) struct RigBuilder<'a> {
    name: String,
    doc: &'a gltf::Document,
    buffers: &'a [&'a [u8]],
    nodes: Vec<NodeRest>,
    visits: Vec<Visit>,
    /// The first visit of each node (`NO_VISIT` if none yet).
    node_visit: Vec<u32>,
    primitives: Vec<Primitive>,
    instances: Vec<Instance>,
    placements: Vec<DMat4>,
    /// Per node, its instancing matrices' range in `placements` (read at its first visit).
    node_placements: Vec<Option<std::ops::Range<u32>>>,
    vertex_count: usize,
    /// Per node, its skin when it has a mesh too.
    node_skin: Vec<Option<u32>>,
    /// Per skinned mesh, the skin with the fewest joints among those applied to it, and a node
    /// applying it: (joints, skin, node).
    mesh_skin: Vec<Option<(usize, usize, usize)>>,
}

impl<'a> RigBuilder<'a> {
    pub fn new(doc: &'a gltf::Document, buffers: &'a [&'a [u8]], name: &str) -> RigBuilder<'a> {
        let nodes = doc
            .nodes()
            .map(|n| {
                let (t, r, s) = n.transform().decomposed();
                NodeRest {
                    matrix: Mat4::from_cols_array_2d(&n.transform().matrix()).as_dmat4(),
                    trs: Trs {
                        translation: Vec3::from(t).as_dvec3(),
                        rotation: DQuat::from_xyzw(r[0] as f64, r[1] as f64, r[2] as f64, r[3] as f64),
                        scale: Vec3::from(s).as_dvec3(),
                    },
                }
            })
            .collect::<Vec<_>>();
        let mut node_skin = vec![None; nodes.len()];
        let mut mesh_skin = vec![None; doc.meshes().len()];
        for n in doc.nodes() {
            if let (Some(skin), Some(mesh)) = (n.skin(), n.mesh()) {
                node_skin[n.index()] = Some(skin.index() as u32);
                let this = (skin.joints().count(), skin.index(), n.index());
                let least: &mut Option<(usize, usize, usize)> = &mut mesh_skin[mesh.index()];
                if least.is_none_or(|l| this.0 < l.0) {
                    *least = Some(this);
                }
            }
        }
        RigBuilder {
            node_skin,
            mesh_skin,
            name: name.into(),
            doc,
            buffers,
            node_visit: vec![NO_VISIT; nodes.len()],
            placements: Vec::new(),
            node_placements: vec![None; nodes.len()],
            nodes,
            visits: Vec::new(),
            primitives: Vec::new(),
            instances: Vec::new(),
            vertex_count: 0,
        }
    }

    /// True when some node skins a mesh with this index (its primitives need influences).
    pub fn mesh_is_skinned(&self, mesh: usize) -> bool {
        self.mesh_skin[mesh].is_some()
    }

    /// Adds a decoded primitive; returns its id for [`RigBuilder::instance`].
    pub fn primitive(
        &mut self,
        prim: &gltf::Primitive,
        at: PrimitiveRef,
        positions: Vec<Vec3>,
        skinned: bool,
    ) -> Result<u32, SceneError> {
        let targets = self.read_targets(prim, &at)?;
        let influences = if skinned { Some(self.read_influences(prim, &at)?) } else { None };
        self.primitives.push(Primitive { at, positions, targets, influences });
        Ok(self.primitives.len() as u32 - 1)
    }

    /// Records a visit of `node` under the visit `parent`.
    pub fn visit(&mut self, node: usize, parent: Option<u32>) -> u32 {
        let v = self.visits.len() as u32;
        self.visits.push(Visit { node: node as u32, parent });
        if self.node_visit[node] == NO_VISIT {
            self.node_visit[node] = v;
        }
        v
    }

    /// The indices of `node`'s instancing matrices (`read` once, at the node's first visit).
    pub fn placements(
        &mut self,
        node: usize,
        read: impl FnOnce() -> Result<Vec<DMat4>, SceneError>,
    ) -> Result<std::ops::Range<u32>, SceneError> {
        if let Some(range) = &self.node_placements[node] {
            return Ok(range.clone());
        }
        let start = self.placements.len() as u32;
        self.placements.extend(read()?);
        let range = start..self.placements.len() as u32;
        self.node_placements[node] = Some(range.clone());
        Ok(range)
    }

    /// Places `primitive` at `visit` (in the instancing `placement` of the node's space, if
    /// any); returns the index of its first vertex.
    pub fn instance(&mut self, visit: u32, node: usize, primitive: u32, placement: Option<u32>) -> u32 {
        let first = self.vertex_count;
        let skinned = self.primitives[primitive as usize].influences.is_some();
        let skin = if skinned { self.node_skin[node] } else { None };
        self.instances.push(Instance { visit, node: node as u32, primitive, skin, placement, first_vertex: first });
        self.vertex_count += self.primitives[primitive as usize].positions.len();
        first as u32
    }

    fn read(&self, acc: &gltf::Accessor) -> Result<Vec<f64>, AccessorFault> {
        read_components(self.buffers, acc)
    }

    fn read_targets(&self, prim: &gltf::Primitive, at: &PrimitiveRef) -> Result<Vec<Vec<Vec3>>, SceneError> {
        let fail =
            |detail: String| SceneError::InvalidMorphTargets { source_name: self.name.clone(), at: at.clone(), detail };
        let mut out = Vec::new();
        for (k, t) in prim.morph_targets().enumerate() {
            out.push(match t.positions() {
                Some(acc) => {
                    let d = self.read(&acc).map_err(|f| fail(format!("target {k}: {f:?}")))?;
                    if let Some(i) = d.iter().position(|v| !v.is_finite()) {
                        return Err(fail(format!("target {k}: vertex {} delta is not finite", i / 3)));
                    }
                    d.chunks_exact(3).map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)).collect()
                }
                None => Vec::new(),
            });
        }
        Ok(out)
    }

    /// JOINTS_n / WEIGHTS_n sets, in pairs.
    fn read_influences(&self, prim: &gltf::Primitive, at: &PrimitiveRef) -> Result<Influences, SceneError> {
        let (limit, skin, node) = self.mesh_skin[at.mesh].expect("only skinned meshes read influences");
        let fail = |detail: String| SceneError::InvalidSkin { source_name: self.name.clone(), skin, detail };
        let vertices = prim.get(&gltf::Semantic::Positions).map_or(0, |p| p.count());
        let mut sets = 0;
        while prim.get(&gltf::Semantic::Joints(sets)).is_some() || prim.get(&gltf::Semantic::Weights(sets)).is_some() {
            sets += 1;
        }
        if sets == 0 {
            return Err(fail(format!("{at}: is skinned but has no JOINTS_0 / WEIGHTS_0")));
        }
        let per_vertex = 4 * sets as usize;
        let mut joints = vec![0u16; vertices * per_vertex];
        let mut weights = vec![0f32; vertices * per_vertex];
        for set in 0..sets {
            let (Some(j), Some(w)) = (prim.get(&gltf::Semantic::Joints(set)), prim.get(&gltf::Semantic::Weights(set)))
            else {
                return Err(fail(format!("{at}: JOINTS_{set} and WEIGHTS_{set} must come in pairs")));
            };
            let weight_type_ok = match w.data_type() {
                DataType::F32 => true,
                DataType::U8 | DataType::U16 => w.normalized(),
                _ => false,
            };
            // Element counts were checked with the shape (animation_data).
            if !weight_type_ok || w.dimensions() != Dimensions::Vec4 {
                return Err(fail(format!(
                    "{at}: WEIGHTS_{set} accessor {} must be float or normalized unsigned byte/short VEC4",
                    w.index()
                )));
            }
            let joints_at = format!(
                "node {node}, mesh {} primitive {}, Joints({set}) accessor {}",
                at.mesh,
                at.primitive,
                j.index()
            );
            let jv = self.read(&j).map_err(|f| fail(format!("{joints_at}: {f:?}")))?;
            if let Some(k) = jv.iter().position(|&x| x as usize >= limit) {
                return Err(fail(format!(
                    "{joints_at}: vertex {} uses joint {}, the skin has {limit} joints",
                    k / 4,
                    jv[k]
                )));
            }
            let wv = self.read(&w).map_err(|f| fail(format!("{at}: WEIGHTS_{set} accessor {}: {f:?}", w.index())))?;
            for v in 0..vertices {
                for c in 0..4 {
                    joints[v * per_vertex + set as usize * 4 + c] = jv[v * 4 + c] as u16;
                    weights[v * per_vertex + set as usize * 4 + c] = wv[v * 4 + c] as f32;
                }
            }
        }
        Ok(Influences { per_vertex, joints, weights })
    }

    /// The skins, the clips and the morph weights; every joint gets a visit (a joint outside
    /// the default scene is placed by its chain of first parents).
    pub fn finish(mut self) -> Result<Rig, SceneError> {
        let doc = self.doc;
        let mut first_parent = vec![None; self.nodes.len()];
        for n in doc.nodes() {
            for c in n.children() {
                first_parent[c.index()].get_or_insert(n.index());
            }
        }
        let mut skins = Vec::new();
        let mut offset = 0;
        for skin in doc.skins() {
            let mut joints = Vec::new();
            for j in skin.joints() {
                joints.push(self.joint_visit(j.index(), &first_parent, skin.index())?);
            }
            let inverse_bind = match skin.inverse_bind_matrices() {
                Some(acc) => {
                    let fail = |detail: String| SceneError::InvalidSkin {
                        source_name: self.name.clone(),
                        skin: skin.index(),
                        detail,
                    };
                    let m = self
                        .read(&acc)
                        .map_err(|f| fail(format!("inverseBindMatrices accessor {}: {f:?}", acc.index())))?;
                    if let Some(k) = m.iter().position(|v| !v.is_finite()) {
                        return Err(fail(format!("inverse bind matrix {} is not finite", k / 16)));
                    }
                    m.chunks_exact(16).take(joints.len()).map(DMat4::from_cols_slice).collect()
                }
                None => vec![DMat4::IDENTITY; joints.len()],
            };
            skins.push(Skin { offset, joints, inverse_bind });
            offset += skins.last().map_or(0, |s: &Skin| s.joints.len());
        }

        // Morph weights: the node's, else the mesh's, else zeros.
        let mut weight_start = vec![0];
        let mut rest_weights = Vec::new();
        for n in doc.nodes() {
            let targets = n.mesh().map_or(0, |m| mesh_targets(&m));
            let given = n.weights().or_else(|| n.mesh().and_then(|m| m.weights()));
            match given {
                Some(w) if w.len() == targets => rest_weights.extend(w.iter().map(|&x| x as f64)),
                _ => rest_weights.extend(std::iter::repeat_n(0.0, targets)),
            }
            weight_start.push(rest_weights.len());
        }

        let clips = doc.animations().map(|a| self.clip(&a)).collect::<Result<Vec<_>, _>>()?;
        Ok(Rig {
            source_name: self.name,
            nodes: self.nodes,
            visits: self.visits,
            primitives: self.primitives,
            instances: self.instances,
            placements: self.placements,
            joint_count: offset,
            skins,
            clips,
            weight_start,
            rest_weights,
            vertex_count: self.vertex_count,
        })
    }

    /// The visit placing joint `node`; visits its chain of first parents when the scene walk
    /// did not reach it.
    fn joint_visit(&mut self, node: usize, first_parent: &[Option<usize>], skin: usize) -> Result<u32, SceneError> {
        let mut chain = Vec::new();
        let mut n = node;
        while self.node_visit[n] == NO_VISIT {
            chain.push(n);
            if chain.len() > MAX_NODE_DEPTH {
                return Err(SceneError::InvalidSkin {
                    source_name: self.name.clone(),
                    skin,
                    detail: format!(
                        "joint node {node} is outside the scene and its ancestry is deeper than {MAX_NODE_DEPTH} levels or a cycle"
                    ),
                });
            }
            match first_parent[n] {
                Some(p) => n = p,
                None => break,
            }
        }
        let mut parent = (self.node_visit[n] != NO_VISIT).then_some(self.node_visit[n]);
        for &c in chain.iter().rev() {
            parent = Some(self.visit(c, parent));
        }
        Ok(self.node_visit[node])
    }

    fn clip(&self, anim: &gltf::Animation) -> Result<Clip, SceneError> {
        let fail = |sampler: usize, detail: String| SceneError::InvalidAnimation {
            source_name: self.name.clone(),
            animation: anim.index(),
            sampler: Some(sampler),
            detail,
        };
        let mut samplers = Vec::new();
        for s in anim.samplers() {
            let si = s.index();
            let (input, output) = (s.input(), s.output());
            let times = self.read(&input).map_err(|f| fail(si, format!("input accessor {}: {f:?}", input.index())))?;
            if let Some(k) = times.iter().position(|t| !t.is_finite()) {
                return Err(fail(si, format!("key {k}'s time is {}", times[k])));
            }
            if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
                return Err(fail(
                    si,
                    format!("key times not strictly increasing: key {} is {} after {}", k + 1, times[k + 1], times[k]),
                ));
            }
            let values =
                self.read(&output).map_err(|f| fail(si, format!("output accessor {}: {f:?}", output.index())))?;
            if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                let n = output.dimensions().multiplicity();
                return Err(fail(si, format!("output value {} (element {}) is {}", k, k / n, values[k])));
            }
            let per_key = if s.interpolation() == gltf::animation::Interpolation::CubicSpline { 3 } else { 1 };
            // Validated: values = keys × per_key × width.
            let width = values.len() / (times.len() * per_key).max(1);
            samplers.push(Sampler { interpolation: s.interpolation().into(), times, values, width });
        }
        let mut channels = Vec::new();
        let (mut moved, mut is_moved) = (Vec::new(), vec![false; self.nodes.len()]);
        for ch in anim.channels() {
            let node = ch.target().node().index() as u32;
            let target = match ch.target().property() {
                Property::Translation => Target::Translation,
                Property::Rotation => Target::Rotation,
                Property::Scale => Target::Scale,
                Property::MorphTargetWeights => Target::Weights,
            };
            let sampler = ch.sampler().index();
            if target == Target::Rotation
                && let Some(k) = samplers.get(sampler).and_then(Sampler::zero_quaternion_key)
            {
                return Err(fail(sampler, format!("rotation key {k} is the zero quaternion (it has no direction)")));
            }
            if target != Target::Weights && !std::mem::replace(&mut is_moved[node as usize], true) {
                moved.push(node);
            }
            channels.push(Channel { node, target, sampler: ch.sampler().index() as u32 });
        }
        let used = || channels.iter().map(|c| samplers[c.sampler as usize].range());
        let start = used().map(|r| r.0).fold(f64::INFINITY, f64::min);
        let end = used().map(|r| r.1).fold(f64::NEG_INFINITY, f64::max);
        let (start, end) = if channels.is_empty() { (0.0, 0.0) } else { (start, end) };
        Ok(Clip { index: anim.index(), name: anim.name().map(str::to_string), start, end, samplers, channels, moved })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn identity_times_a_matrix_is_the_matrix() {
        // The rest pose relies on it: a root's world is IDENTITY * local, bit for bit.
        let m = DMat4::from_scale_rotation_translation(
            DVec3::new(0.3, 1.7, 2.1),
            DQuat::from_rotation_y(0.7),
            DVec3::new(-1.1, 3.3, 1e-7),
        );
        assert_eq!((DMat4::IDENTITY * m).to_cols_array(), m.to_cols_array());
    }
}
