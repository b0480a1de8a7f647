//! Validation of the shape of the data that poses a glTF scene — animation samplers, skins and
//! morph targets — from the JSON alone, before any of it is decoded: the glTF 2.0 rules on
//! accessor types, output counts matching the keys (×3 for CUBICSPLINE, × morph targets for
//! weights), one JOINTS/WEIGHTS element per vertex, enough inverse bind matrices, and morph
//! target counts that agree within a mesh. The values themselves (times finite and strictly
//! increasing, finite outputs, matrices and deltas, joint indices inside the skin) are checked
//! where they are decoded, once, by [`crate::pose`]'s builder. Element counts were already
//! checked by [`crate::load_budget`].

use gltf::Document;
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::{Interpolation, Property};

use crate::error::{PrimitiveRef, SceneError};

/// Checks the shape of every animation, skin and morph target of `doc`.
pub(crate) fn validate(doc: &Document, name: &str) -> Result<(), SceneError> {
    for anim in doc.animations() {
        let fail = |sampler: Option<usize>, detail: String| SceneError::InvalidAnimation {
            source_name: name.into(),
            animation: anim.index(),
            sampler,
            detail,
        };
        for s in anim.samplers() {
            let si = Some(s.index());
            let input = s.input();
            if input.data_type() != DataType::F32 || input.dimensions() != Dimensions::Scalar {
                return Err(fail(si, format!("input accessor {} must be float SCALAR times", input.index())));
            }
            if input.count() == 0 {
                return Err(fail(si, format!("input accessor {} has no keys", input.index())));
            }
            if s.interpolation() == Interpolation::CubicSpline && input.count() < 2 {
                return Err(fail(si, "CUBICSPLINE needs at least two keys".into()));
            }
        }
        for ch in anim.channels() {
            let s = ch.sampler();
            let si = Some(s.index());
            let keys = s.input().count();
            let per_key = if s.interpolation() == Interpolation::CubicSpline { 3 } else { 1 };
            let node = ch.target().node();
            let (dims, elements) = match ch.target().property() {
                Property::Translation | Property::Scale => (Dimensions::Vec3, 1),
                Property::Rotation => (Dimensions::Vec4, 1),
                Property::MorphTargetWeights => {
                    let targets = node.mesh().map_or(0, |m| mesh_targets(&m));
                    if targets == 0 {
                        return Err(fail(
                            si,
                            format!(
                                "channel {} animates weights of node {}, which has no morph targets",
                                ch.index(),
                                node.index()
                            ),
                        ));
                    }
                    (Dimensions::Scalar, targets)
                }
            };
            let output = s.output();
            if output.dimensions() != dims {
                return Err(fail(
                    si,
                    format!(
                        "output accessor {} is {:?}, channel {} needs {dims:?}",
                        output.index(),
                        output.dimensions(),
                        ch.index()
                    ),
                ));
            }
            let expected = keys as u64 * per_key * elements as u64;
            if output.count() as u64 != expected {
                return Err(fail(
                    si,
                    format!(
                        "output accessor {} has {} elements, channel {} needs {expected} ({keys} keys × {per_key} × {elements})",
                        output.index(),
                        output.count(),
                        ch.index()
                    ),
                ));
            }
        }
    }

    for skin in doc.skins() {
        let fail = |detail: String| SceneError::InvalidSkin { source_name: name.into(), skin: skin.index(), detail };
        let joints = skin.joints().count();
        if joints == 0 {
            return Err(fail("has no joints".into()));
        }
        if let Some(acc) = skin.inverse_bind_matrices() {
            if acc.data_type() != DataType::F32 || acc.dimensions() != Dimensions::Mat4 {
                return Err(fail(format!("inverseBindMatrices accessor {} must be float MAT4", acc.index())));
            }
            if acc.count() < joints {
                return Err(fail(format!(
                    "inverseBindMatrices accessor {} has {} matrices for {joints} joints",
                    acc.index(),
                    acc.count()
                )));
            }
        }
    }

    // Skinned meshes: one joint and one weight element per vertex, joints as small integers.
    for node in doc.nodes() {
        let (Some(skin), Some(mesh)) = (node.skin(), node.mesh()) else { continue };
        let fail = |detail: String| SceneError::InvalidSkin { source_name: name.into(), skin: skin.index(), detail };
        for prim in mesh.primitives() {
            let vertices = prim.get(&gltf::Semantic::Positions).map_or(0, |p| p.count());
            for (sem, acc) in prim.attributes() {
                let is_joints = matches!(sem, gltf::Semantic::Joints(_));
                if !(is_joints || matches!(sem, gltf::Semantic::Weights(_))) {
                    continue;
                }
                let at = format!(
                    "node {}, mesh {} primitive {}, {sem:?} accessor {}",
                    node.index(),
                    mesh.index(),
                    prim.index(),
                    acc.index()
                );
                if acc.count() != vertices {
                    return Err(fail(format!("{at} has {} elements for {vertices} vertices", acc.count())));
                }
                if is_joints
                    && (!matches!(acc.data_type(), DataType::U8 | DataType::U16)
                        || acc.dimensions() != Dimensions::Vec4)
                {
                    return Err(fail(format!("{at} must be unsigned byte or short VEC4")));
                }
            }
        }
    }

    // Morph targets: one POSITION delta per vertex, the same number of targets in every
    // primitive of a mesh, default weights that match.
    for mesh in doc.meshes() {
        let targets = mesh_targets(&mesh);
        for prim in mesh.primitives() {
            let at = PrimitiveRef {
                mesh: mesh.index(),
                mesh_name: mesh.name().map(str::to_string),
                primitive: prim.index(),
            };
            let fail =
                |detail: String| SceneError::InvalidMorphTargets { source_name: name.into(), at: at.clone(), detail };
            let n = prim.morph_targets().count();
            if n != targets {
                return Err(fail(format!("{n} targets, the mesh's first primitive has {targets}")));
            }
            let vertices = prim.get(&gltf::Semantic::Positions).map_or(0, |p| p.count());
            for (k, t) in prim.morph_targets().enumerate() {
                if let Some(acc) = t.positions()
                    && (acc.count() != vertices || acc.dimensions() != Dimensions::Vec3)
                {
                    return Err(fail(format!(
                        "target {k}'s POSITION accessor {} has {} {:?} elements for {vertices} vertices",
                        acc.index(),
                        acc.count(),
                        acc.dimensions()
                    )));
                }
            }
        }
        if let Some(w) = mesh.weights()
            && w.len() != targets
        {
            return Err(SceneError::InvalidMorphTargets {
                source_name: name.into(),
                at: PrimitiveRef { mesh: mesh.index(), mesh_name: mesh.name().map(str::to_string), primitive: 0 },
                detail: format!("the mesh has {} default weights for {targets} targets", w.len()),
            });
        }
    }
    for node in doc.nodes() {
        if let (Some(w), Some(mesh)) = (node.weights(), node.mesh())
            && w.len() != mesh_targets(&mesh)
        {
            return Err(SceneError::InvalidNode {
                source_name: name.into(),
                node: node.index(),
                detail: format!(
                    "{} weights for {} morph targets of mesh {}",
                    w.len(),
                    mesh_targets(&mesh),
                    mesh.index()
                ),
            });
        }
    }
    Ok(())
}

/// Morph targets of a mesh (those of its first primitive; all must agree).
pub(crate) fn mesh_targets(mesh: &gltf::Mesh) -> usize {
    mesh.primitives().next().map_or(0, |p| p.morph_targets().count())
}
