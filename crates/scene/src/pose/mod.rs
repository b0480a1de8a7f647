//! Posing: a glTF scene's triangles at time t of one of its animations.
//!
//! The loader keeps what posing needs as a [`Rig`]: every node's rest transform, the visits of
//! the default scene's node graph (parents first), each mesh instance in triangle order with
//! its primitive's local positions, morph target deltas and joint influences, the skins and the
//! clips. [`Rig::pose`] evaluates a clip at a time and writes world-space positions for the
//! same index list the loader returned, so triangle `i` stays triangle `i` in every frame:
//!
//! 1. node TRS channels (`STEP`, `LINEAR` with quaternion slerp, `CUBICSPLINE`) and morph
//!    weight channels at `t`, clamped to the clip ([`sampler`]);
//! 2. world matrices down the visits (f64);
//! 3. per vertex: base position plus the weighted morph target deltas, then either the
//!    instance's world matrix or — for a skinned mesh, whose own node transform and parents
//!    are ignored by the glTF rule — the weighted sum of joint world × inverse bind matrices.
//!
//! With no clip, the rest pose is the one `load` returns: the loader itself poses through here.
//! A pose reuses its [`PoseScratch`] and position buffer (no allocation after the first frame)
//! and runs the vertices on all threads (feature `parallel`, on by default; off in the browser).

mod build;
pub mod player;
pub(crate) mod sampler;

use glam::{DMat4, DQuat, DVec3, Vec3};
#[cfg(feature = "parallel")]
use rayon::prelude::*;
use serde::Serialize;

pub(crate) use build::RigBuilder;

use crate::error::{PrimitiveRef, SceneError};
use crate::gltf_load::MAX_COORDINATE;
use sampler::Sampler;

/// Vertices per parallel work item.
const VERTEX_CHUNK: usize = 4096;

/// Which clip, and when (seconds on the clip's own time line, as in the file).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipTime {
    pub clip: usize,
    pub seconds: f64,
}

/// Which pose a mesh shows, for reports.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseNote {
    pub clip: usize,
    pub name: Option<String>,
    /// The time asked for, and the time used (clamped to the clip).
    pub seconds: f64,
    pub clamped: f64,
}

impl std::fmt::Display for PoseNote {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = self.name.as_deref().map(|n| format!(" {n:?}")).unwrap_or_default();
        write!(f, "animation {}{name}, t = {} s", self.clip, self.seconds)?;
        if self.clamped != self.seconds {
            write!(f, " (clamped to {} s)", self.clamped)?;
        }
        Ok(())
    }
}

/// One glTF animation.
#[derive(Clone, Debug)]
pub struct Clip {
    pub index: usize,
    pub name: Option<String>,
    /// First and last key time over all of its samplers (0, 0 for a clip with no channels).
    pub start: f64,
    pub end: f64,
    samplers: Vec<Sampler>,
    channels: Vec<Channel>,
    /// Nodes whose translation, rotation or scale this clip drives.
    moved: Vec<u32>,
}

impl Clip {
    pub fn duration(&self) -> f64 {
        self.end - self.start
    }

    /// Number of channels (node properties driven).
    pub fn channel_count(&self) -> usize {
        self.channels.len()
    }

    /// `seconds` clamped to the clip (NaN → its start).
    pub fn clamp(&self, seconds: f64) -> f64 {
        if seconds.is_nan() { self.start } else { seconds.clamp(self.start, self.end) }
    }

    /// A playback time `seconds` after the clip's start, looped over its duration.
    pub fn looped(&self, seconds: f64) -> f64 {
        let d = self.duration();
        if d > 0.0 && seconds.is_finite() { self.start + seconds.rem_euclid(d) } else { self.start }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Target {
    Translation,
    Rotation,
    Scale,
    Weights,
}

#[derive(Clone, Copy, Debug)]
struct Channel {
    node: u32,
    target: Target,
    sampler: u32,
}

/// A node's rest transform: the matrix the static loader uses, and its TRS for animation.
#[derive(Clone, Copy, Debug)]
struct NodeRest {
    matrix: DMat4,
    trs: Trs,
}

#[derive(Clone, Copy, Debug)]
struct Trs {
    translation: DVec3,
    rotation: DQuat,
    scale: DVec3,
}

/// One visit of a node in the default scene's graph; parents come before children.
#[derive(Clone, Copy, Debug)]
struct Visit {
    node: u32,
    parent: Option<u32>,
}

/// A primitive in its mesh's local space.
#[derive(Clone, Debug)]
struct Primitive {
    at: PrimitiveRef,
    positions: Vec<Vec3>,
    /// POSITION deltas per morph target (empty for a target without POSITION).
    targets: Vec<Vec<Vec3>>,
    influences: Option<Influences>,
}

/// Joint influences: `per_vertex` (4 per JOINTS_n/WEIGHTS_n set) joints and weights a vertex.
#[derive(Clone, Debug)]
struct Influences {
    per_vertex: usize,
    joints: Vec<u16>,
    weights: Vec<f32>,
}

/// A primitive placed by a node visit; its vertices start at `first_vertex` in the output.
#[derive(Clone, Copy, Debug)]
struct Instance {
    visit: u32,
    node: u32,
    primitive: u32,
    skin: Option<u32>,
    /// An `EXT_mesh_gpu_instancing` instance's placement in the node's space (its index in
    /// [`Rig::placements`]).
    placement: Option<u32>,
    first_vertex: usize,
}

#[derive(Clone, Debug)]
struct Skin {
    /// The visit that places each joint.
    joints: Vec<u32>,
    inverse_bind: Vec<DMat4>,
    /// Where its joint matrices start in [`PoseScratch::joints`].
    offset: usize,
}

/// Everything needed to pose a loaded glTF scene. Built by the loader; immutable and shared.
#[derive(Clone, Debug)]
pub struct Rig {
    source_name: String,
    nodes: Vec<NodeRest>,
    visits: Vec<Visit>,
    primitives: Vec<Primitive>,
    instances: Vec<Instance>,
    /// The instancing extension's matrices (T · R · S, applied before the node's transform).
    placements: Vec<DMat4>,
    skins: Vec<Skin>,
    clips: Vec<Clip>,
    /// Per node, its morph weights in [`Rig::rest_weights`]: `weight_start[n]..weight_start[n + 1]`.
    weight_start: Vec<usize>,
    rest_weights: Vec<f64>,
    vertex_count: usize,
    joint_count: usize,
}

/// Buffers one pose reuses for the next.
#[derive(Clone, Debug, Default)]
pub struct PoseScratch {
    trs: Vec<Trs>,
    local: Vec<DMat4>,
    world: Vec<DMat4>,
    joints: Vec<DMat4>,
    weights: Vec<f64>,
    value: Vec<f64>,
}

/// What `gridrt info` and the app list about a file's animation.
#[derive(Clone, Debug, Default, Serialize)]
pub struct AnimationSummary {
    pub clips: Vec<ClipSummary>,
    pub skins: usize,
    pub joints: usize,
    /// Morph targets summed over the meshes that have them.
    pub morph_targets: usize,
    pub skinned_instances: usize,
    pub morphed_instances: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct ClipSummary {
    pub index: usize,
    pub name: Option<String>,
    pub start: f64,
    pub end: f64,
    pub channels: usize,
}

impl Rig {
    pub fn clips(&self) -> &[Clip] {
        &self.clips
    }

    /// The clip named by `key`: an index (`0`, `1`, …) or a name.
    pub fn find_clip(&self, key: &str) -> Result<usize, SceneError> {
        if let Ok(i) = key.trim().parse::<usize>()
            && i < self.clips.len()
        {
            return Ok(i);
        }
        if let Some(c) = self.clips.iter().find(|c| c.name.as_deref() == Some(key)) {
            return Ok(c.index);
        }
        let available = if self.clips.is_empty() {
            "no animations".to_string()
        } else {
            let names: Vec<String> = self
                .clips
                .iter()
                .map(|c| match &c.name {
                    Some(n) => format!("{} {n:?}", c.index),
                    None => c.index.to_string(),
                })
                .collect();
            format!("animations {}", names.join(", "))
        };
        Err(SceneError::UnknownAnimation { source_name: self.source_name.clone(), key: key.into(), available })
    }

    /// The report line for a pose at `time`.
    pub fn note(&self, time: ClipTime) -> Option<PoseNote> {
        let c = self.clips.get(time.clip)?;
        Some(PoseNote { clip: c.index, name: c.name.clone(), seconds: time.seconds, clamped: c.clamp(time.seconds) })
    }

    /// What to report about the file's animation (`None` when it has no clips, skins or morph
    /// targets).
    pub fn summary_if_any(&self) -> Option<AnimationSummary> {
        let s = self.summary();
        (!s.clips.is_empty() || s.skins > 0 || s.morph_targets > 0).then_some(s)
    }

    pub fn summary(&self) -> AnimationSummary {
        let mut seen = std::collections::HashSet::new();
        let morph_targets = self.primitives.iter().filter(|p| seen.insert(p.at.mesh)).map(|p| p.targets.len()).sum();
        AnimationSummary {
            clips: self
                .clips
                .iter()
                .map(|c| ClipSummary {
                    index: c.index,
                    name: c.name.clone(),
                    start: c.start,
                    end: c.end,
                    channels: c.channels.len(),
                })
                .collect(),
            skins: self.skins.len(),
            joints: self.joint_count,
            morph_targets,
            skinned_instances: self.instances.iter().filter(|i| i.skin.is_some()).count(),
            morphed_instances: self
                .instances
                .iter()
                .filter(|i| !self.primitives[i.primitive as usize].targets.is_empty())
                .count(),
        }
    }

    /// Writes the world-space positions at `time` (`None`: the rest pose) into `positions`,
    /// resized to the loaded mesh's vertex count. The index list is the loader's and never changes.
    /// Errors when a posed vertex is not finite or beyond [`MAX_COORDINATE`].
    pub fn pose(
        &self,
        time: Option<ClipTime>,
        scratch: &mut PoseScratch,
        positions: &mut Vec<Vec3>,
    ) -> Result<(), SceneError> {
        self.pose_nodes(time, scratch);
        positions.resize(self.vertex_count, Vec3::ZERO);
        #[cfg(feature = "parallel")]
        let chunks = positions.par_chunks_mut(VERTEX_CHUNK);
        #[cfg(not(feature = "parallel"))]
        let chunks = positions.chunks_mut(VERTEX_CHUNK);
        let bad = chunks
            .enumerate()
            .filter_map(|(c, chunk)| self.pose_vertices(c * VERTEX_CHUNK, chunk, scratch))
            .min_by_key(|&(v, _)| v);
        match bad {
            None => Ok(()),
            Some((v, value)) => {
                let err = self.vertex_error(v, value);
                Err(match time {
                    Some(t) => SceneError::AtTime { clip: t.clip, seconds: t.seconds, inner: Box::new(err) },
                    None => err,
                })
            }
        }
    }

    /// Steps 1–2 and the joint matrices: everything but the vertices.
    fn pose_nodes(&self, time: Option<ClipTime>, s: &mut PoseScratch) {
        s.local.clear();
        s.local.extend(self.nodes.iter().map(|n| n.matrix));
        s.weights.clear();
        s.weights.extend_from_slice(&self.rest_weights);
        if let Some(ClipTime { clip, seconds }) = time
            && let Some(clip) = self.clips.get(clip)
        {
            let t = clip.clamp(seconds);
            s.trs.clear();
            s.trs.extend(self.nodes.iter().map(|n| n.trs));
            for ch in &clip.channels {
                let sampler = &clip.samplers[ch.sampler as usize];
                s.value.resize(sampler.width, 0.0);
                sampler.sample(t, ch.target == Target::Rotation, &mut s.value);
                let v = &s.value;
                let node = ch.node as usize;
                let trs = &mut s.trs[node];
                match ch.target {
                    Target::Translation => trs.translation = DVec3::new(v[0], v[1], v[2]),
                    Target::Rotation => trs.rotation = DQuat::from_xyzw(v[0], v[1], v[2], v[3]).normalize(),
                    Target::Scale => trs.scale = DVec3::new(v[0], v[1], v[2]),
                    Target::Weights => {
                        let w = &mut s.weights[self.weight_start[node]..self.weight_start[node + 1]];
                        w.copy_from_slice(&v[..w.len()]);
                    }
                }
            }
            for &n in &clip.moved {
                let t = s.trs[n as usize];
                s.local[n as usize] = DMat4::from_scale_rotation_translation(t.scale, t.rotation, t.translation);
            }
        }
        s.world.clear();
        for v in &self.visits {
            let parent = v.parent.map_or(DMat4::IDENTITY, |p| s.world[p as usize]);
            s.world.push(parent * s.local[v.node as usize]);
        }
        s.joints.clear();
        for skin in &self.skins {
            debug_assert_eq!(skin.offset, s.joints.len());
            s.joints.extend(skin.joints.iter().zip(&skin.inverse_bind).map(|(&v, ibm)| s.world[v as usize] * *ibm));
        }
    }

    /// Poses the vertices `first..first + out.len()`; the first one that cannot be held, if any.
    fn pose_vertices(&self, first: usize, out: &mut [Vec3], s: &PoseScratch) -> Option<(usize, Vec3)> {
        let mut i = self.instances.partition_point(|inst| inst.first_vertex <= first) - 1;
        let mut v = first;
        let end = first + out.len();
        let mut bad = None;
        while v < end {
            let inst = &self.instances[i];
            let prim = &self.primitives[inst.primitive as usize];
            let stop = end.min(inst.first_vertex + prim.positions.len());
            let local = v - inst.first_vertex..stop - inst.first_vertex;
            let dst = &mut out[v - first..stop - first];
            let node = inst.node as usize;
            let weights = &s.weights[self.weight_start[node]..self.weight_start[node + 1]];
            let morph = |k: usize| -> DVec3 {
                let mut p = prim.positions[k].as_dvec3();
                for (w, d) in weights.iter().zip(&prim.targets) {
                    if *w != 0.0 && !d.is_empty() {
                        p += d[k].as_dvec3() * *w;
                    }
                }
                p
            };
            match (inst.skin, &prim.influences) {
                (Some(skin), Some(inf)) => {
                    let joints = &s.joints[self.skins[skin as usize].offset..];
                    for (k, o) in local.zip(dst.iter_mut()) {
                        let mut m = DMat4::ZERO;
                        let range = k * inf.per_vertex..(k + 1) * inf.per_vertex;
                        for (&j, &w) in inf.joints[range.clone()].iter().zip(&inf.weights[range]) {
                            if w != 0.0 {
                                m += joints[j as usize] * w as f64;
                            }
                        }
                        *o = m.transform_point3(morph(k)).as_vec3();
                    }
                }
                _ => {
                    let m = s.world[inst.visit as usize];
                    let m = inst.placement.map_or(m, |p| m * self.placements[p as usize]);
                    for (k, o) in local.zip(dst.iter_mut()) {
                        *o = m.transform_point3(morph(k)).as_vec3();
                    }
                }
            }
            if bad.is_none()
                && let Some(k) = dst.iter().position(|p| !p.is_finite() || p.abs().max_element() > MAX_COORDINATE)
            {
                bad = Some((v + k, dst[k]));
            }
            v = stop;
            i += 1;
        }
        bad
    }

    /// The error naming the node, primitive and vertex of output vertex `v`.
    fn vertex_error(&self, v: usize, value: Vec3) -> SceneError {
        let i = self.instances.partition_point(|inst| inst.first_vertex <= v) - 1;
        let inst = &self.instances[i];
        let at = self.primitives[inst.primitive as usize].at.clone();
        let (source_name, node, vertex) = (self.source_name.clone(), inst.node as usize, v - inst.first_vertex);
        if value.is_finite() {
            SceneError::CoordinateOutOfRange {
                source_name,
                at,
                node,
                vertex,
                value: value.to_array(),
                limit: MAX_COORDINATE,
            }
        } else {
            SceneError::NonFiniteVertex { source_name, at, node: Some(node), vertex, value: value.to_array() }
        }
    }
}
