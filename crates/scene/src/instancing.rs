//! `EXT_mesh_gpu_instancing`: a node's mesh drawn once per instance, each instance placed by its
//! own translation, rotation and scale (accessors named in the node's extension object) inside
//! the node's space. The loader expands the instances into triangles (instance after instance,
//! each with the mesh's primitives in order); the load budget parses and counts them first
//! ([`NodeInstancing::of`], once per node), the walk reads each node's matrices at its first
//! visit ([`NodeInstancing::matrices`]).

use glam::{DMat4, DQuat, DVec3};
use gltf::accessor::{DataType, Dimensions};

use crate::accessor::read_components;
use crate::error::SceneError;

/// The extension's name, as files list it in `extensionsUsed` / `extensionsRequired`.
pub(crate) const MESH_GPU_INSTANCING: &str = "EXT_mesh_gpu_instancing";

/// The instancing of one node: its attributes' accessors and the instance count they share.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct NodeInstancing {
    translation: Option<usize>,
    rotation: Option<usize>,
    scale: Option<usize>,
    /// Instances (every attribute's element count).
    pub count: usize,
}

/// The attributes the extension defines and their accessor types (the component types are checked in
/// [`NodeInstancing::of`]: float, and for ROTATION also normalized byte or short).
const ATTRIBUTES: [(&str, Dimensions); 3] =
    [("TRANSLATION", Dimensions::Vec3), ("ROTATION", Dimensions::Vec4), ("SCALE", Dimensions::Vec3)];

/// The error for node `node`'s malformed instancing.
fn invalid(name: &str, node: usize, detail: String) -> SceneError {
    SceneError::InvalidNode { source_name: name.into(), node, detail: format!("{MESH_GPU_INSTANCING}: {detail}") }
}

impl NodeInstancing {
    /// The instancing of `node`, or `None` when it has none; an error for an extension object
    /// that is malformed (attributes missing or not accessor indices, an accessor that does not
    /// exist or has the wrong type, counts that differ) or on a node without a mesh or with a
    /// skin (the extension defines neither).
    pub(crate) fn of(
        doc: &gltf::Document,
        node: &gltf::Node,
        name: &str,
    ) -> Result<Option<NodeInstancing>, SceneError> {
        let Some(ext) = node.extension_value(MESH_GPU_INSTANCING) else { return Ok(None) };
        let fail = |detail: String| invalid(name, node.index(), detail);
        if node.mesh().is_none() {
            return Err(fail("the node has no mesh to instance".into()));
        }
        if node.skin().is_some() {
            return Err(fail("instancing a skinned mesh is not defined".into()));
        }
        let attrs =
            ext.get("attributes").and_then(|a| a.as_object()).ok_or_else(|| fail("no \"attributes\" object".into()))?;
        let mut found = [None; 3];
        let mut count = None;
        for (k, (attr, dims)) in ATTRIBUTES.iter().enumerate() {
            let Some(v) = attrs.get(*attr) else { continue };
            let index = v
                .as_u64()
                .and_then(|i| usize::try_from(i).ok())
                .ok_or_else(|| fail(format!("{attr}: {v} is not an accessor index")))?;
            let acc =
                doc.accessors().nth(index).ok_or_else(|| fail(format!("{attr}: accessor {index} does not exist")))?;
            let t = acc.data_type();
            let types_ok = match *attr {
                "ROTATION" => t == DataType::F32 || (matches!(t, DataType::I8 | DataType::I16) && acc.normalized()),
                _ => t == DataType::F32,
            };
            if acc.dimensions() != *dims || !types_ok {
                return Err(fail(format!(
                    "{attr}: accessor {index} is {:?} {t:?}{}; the extension wants {dims:?} float{}",
                    acc.dimensions(),
                    if acc.normalized() { " normalized" } else { "" },
                    if *attr == "ROTATION" { " (or normalized byte / short)" } else { "" }
                )));
            }
            if count.is_some_and(|c| c != acc.count()) {
                return Err(fail(format!(
                    "{attr}: accessor {index} has {} elements, another attribute {}",
                    acc.count(),
                    count.unwrap_or(0)
                )));
            }
            count = Some(acc.count());
            found[k] = Some(index);
        }
        let Some(count) = count else {
            return Err(fail("none of TRANSLATION, ROTATION, SCALE is given".into()));
        };
        let [translation, rotation, scale] = found;
        Ok(Some(NodeInstancing { translation, rotation, scale, count }))
    }

    /// Bytes reading an instance allocates (its components as f64, then its matrix).
    pub(crate) fn bytes_per_instance(&self) -> u64 {
        let components: u64 = [self.translation, self.rotation, self.scale]
            .iter()
            .zip([3u64, 4, 3])
            .filter_map(|(a, n)| a.map(|_| n))
            .sum();
        components * 8 + 128
    }

    /// Each instance's matrix T · R · S (the node's transform applies on top of it); an error for
    /// a value that is not finite or a rotation of length zero.
    pub(crate) fn matrices(
        &self,
        doc: &gltf::Document,
        buffers: &[&[u8]],
        node: usize,
        name: &str,
    ) -> Result<Vec<DMat4>, SceneError> {
        let fail = |detail: String| invalid(name, node, detail);
        let read = |index: Option<usize>, attr: &str| -> Result<Option<Vec<f64>>, SceneError> {
            let Some(index) = index else { return Ok(None) };
            let acc = doc.accessors().nth(index).expect("checked when parsed");
            let values = read_components(buffers, &acc).map_err(|f| fail(format!("{attr} accessor {index}: {f:?}")))?;
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(fail(format!(
                    "{attr} accessor {index}: instance {} is not finite",
                    i / acc.dimensions().multiplicity()
                )));
            }
            Ok(Some(values))
        };
        let t = read(self.translation, "TRANSLATION")?;
        let r = read(self.rotation, "ROTATION")?;
        let s = read(self.scale, "SCALE")?;
        (0..self.count)
            .map(|i| {
                let v3 = |a: &Option<Vec<f64>>, default: DVec3| {
                    a.as_ref().map_or(default, |a| DVec3::new(a[3 * i], a[3 * i + 1], a[3 * i + 2]))
                };
                let rotation = match &r {
                    Some(r) => {
                        let q = DQuat::from_xyzw(r[4 * i], r[4 * i + 1], r[4 * i + 2], r[4 * i + 3]);
                        if q.length_squared() == 0.0 {
                            return Err(fail(format!("ROTATION of instance {i} is the zero quaternion")));
                        }
                        q.normalize()
                    }
                    None => DQuat::IDENTITY,
                };
                Ok(DMat4::from_scale_rotation_translation(v3(&s, DVec3::ONE), rotation, v3(&t, DVec3::ZERO)))
            })
            .collect()
    }
}
