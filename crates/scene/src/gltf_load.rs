//! glTF 2.0 loading (`.gltf` with embedded or external buffers, and `.glb`) into one [`Mesh`].
//!
//! # Triangle order (public contract)
//! Hit files name triangles by index, so the order is fixed and documented:
//! 1. the nodes of the default scene (or scene 0 when none is marked default; or, in a file with
//!    no scenes, every root node in index order) are visited **depth-first in document order**:
//!    a node, then its children in the order of its `children` array;
//! 2. for each visited node with a mesh, that mesh's primitives in order; a node with
//!    `EXT_mesh_gpu_instancing` repeats them once per instance, in instance order;
//! 3. within a primitive, triangles in index order: `TRIANGLES` takes indices `3i, 3i+1, 3i+2`;
//!    `TRIANGLE_STRIP` triangle `i` is `(i, i+1, i+2)` for even `i` and `(i+1, i, i+2)` for odd
//!    `i` (the glTF winding rule); `TRIANGLE_FAN` triangle `i` is `(i+1, i+2, 0)`.
//!    Non-indexed primitives use the vertex order as the index sequence.
//!
//! Degenerate (zero-area) triangles are kept, so that indices stay aligned with the file; they
//! never produce a hit. Primitives of other modes (points, lines) are skipped and reported.
//!
//! # Robustness
//! Before a buffer is read, [`crate::gltf_file`] checks the container, the JSON and the buffer
//! URIs, and [`crate::load_budget`] counts what the document would allocate (instancing through
//! the node graph included) against [`LoadLimits`]. Accessors are read with explicit bounds
//! checks ([`crate::accessor`]); the shape of animation and skin data is validated
//! ([`crate::animation_data`]) and their values where the rig decodes them ([`crate::pose`]), so every malformed file gets a [`SceneError`] naming the node,
//! mesh, primitive or accessor at fault instead of a panic, an abort or a hang.

use std::path::Path;

use glam::Vec3;
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use crate::accessor::{AccessorFault, read_components, read_uint, view_bytes};
use crate::error::{PrimitiveRef, SceneError};
pub use crate::gltf_file::MAX_FILE_BYTES;
use crate::gltf_file::{map_gltf_error, precheck, precheck_external_buffers, read_file_bounded, validate};
use crate::instancing::NodeInstancing;
pub use crate::load_budget::{LoadLimits, MAX_TRIANGLES};
use crate::mesh::{LoadReport, Mesh};
use crate::pose::{PoseScratch, Rig, RigBuilder};

/// Largest coordinate magnitude after transforms: keeps every extent and grid computation
/// finite in f32 (extents up to 2e30, products of cell counts far from overflow).
pub const MAX_COORDINATE: f32 = 1e30;
/// Largest node depth (guards against hierarchies crafted to exhaust the stack).
pub const MAX_NODE_DEPTH: usize = 256;

/// A loaded scene with what it takes to pose it: `mesh` is the rest pose (no animation
/// applied), `rig` poses it at any time of any clip into the same index list.
#[derive(Clone, Debug)]
pub struct Loaded {
    pub mesh: Mesh,
    pub rig: Rig,
    pub report: LoadReport,
}

/// Loads a `.gltf` or `.glb` file; external buffers are resolved next to it.
/// With the default [`LoadLimits`].
pub fn load_path(path: &Path) -> Result<(Mesh, LoadReport), SceneError> {
    load_path_with(path, &LoadLimits::default())
}

/// Loads a `.gltf` or `.glb` file within `limits`; external buffers are resolved next to it.
pub fn load_path_with(path: &Path, limits: &LoadLimits) -> Result<(Mesh, LoadReport), SceneError> {
    load_rigged_path_with(path, limits).map(|l| (l.mesh, l.report))
}

/// Loads a file with its [`Rig`] (for posing at animation times).
pub fn load_rigged_path_with(path: &Path, limits: &LoadLimits) -> Result<Loaded, SceneError> {
    let name = path.display().to_string();
    let bytes = read_file_bounded(path, &name, limits)?;
    load_rigged_slice_with(&bytes, &name, path.parent(), limits)
}

/// Loads glTF from memory with the default [`LoadLimits`].
pub fn load_slice(bytes: &[u8], source_name: &str, base_dir: Option<&Path>) -> Result<(Mesh, LoadReport), SceneError> {
    load_slice_with(bytes, source_name, base_dir, &LoadLimits::default())
}

/// Loads glTF from memory within `limits`. `source_name` is used in errors and the report;
/// `base_dir` resolves external buffer URIs (`None`: only embedded data and the GLB chunk are
/// allowed).
pub fn load_slice_with(
    bytes: &[u8],
    source_name: &str,
    base_dir: Option<&Path>,
    limits: &LoadLimits,
) -> Result<(Mesh, LoadReport), SceneError> {
    load_rigged_slice_with(bytes, source_name, base_dir, limits).map(|l| (l.mesh, l.report))
}

/// [`load_slice_with`], keeping the [`Rig`].
pub fn load_rigged_slice_with(
    bytes: &[u8],
    source_name: &str,
    base_dir: Option<&Path>,
    limits: &LoadLimits,
) -> Result<Loaded, SceneError> {
    let name = source_name.to_string();
    precheck(bytes, &name)?;
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| map_gltf_error(e, &name))?;
    let doc = gltf.document;
    validate(&doc, &name)?;
    let roots = root_nodes(&doc);
    let plan = crate::load_budget::check(&doc, &roots, limits, bytes.len() as u64, &name)?;
    precheck_external_buffers(&doc, base_dir, &name)?;
    let buffers = gltf::import_buffers(&doc, base_dir, gltf.blob).map_err(|e| map_gltf_error(e, &name))?;
    let buffers: Vec<&[u8]> = buffers.iter().map(|d| &d.0[..]).collect();
    crate::animation_data::validate(&doc, &name)?;
    let quantized = doc.extensions_used().any(|e| e == MESH_QUANTIZATION);
    Loader { name, doc: &doc, buffers: &buffers, quantized }.load(&roots, plan)
}

/// The root nodes of the default scene (or scene 0 when none is marked default; or, in a file
/// with no scenes, every node that is nobody's child), in order.
fn root_nodes(doc: &gltf::Document) -> Vec<usize> {
    match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().map(|n| n.index()).collect(),
        None => {
            let mut is_child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            (0..is_child.len()).filter(|&i| !is_child[i]).collect()
        }
    }
}

/// The extension that allows integer positions (decoded in [`Loader::decode_primitive`]).
pub(crate) const MESH_QUANTIZATION: &str = "KHR_mesh_quantization";

struct Loader<'a> {
    name: String,
    doc: &'a gltf::Document,
    buffers: &'a [&'a [u8]],
    /// Whether the file uses KHR_mesh_quantization (integer positions allowed).
    quantized: bool,
}

/// What the depth-first walk of the scene carries: the decoded meshes, which subtrees to
/// enter, the index list being written, the current path (cycle and depth checks) and the rig.
struct SceneWalk<'w, 'r> {
    meshes: &'w [Vec<Option<LocalPrimitive>>],
    visit_below: &'w [bool],
    instancing: &'w [Option<NodeInstancing>],
    out: &'w mut Mesh,
    path: Vec<usize>,
    rig: &'w mut RigBuilder<'r>,
}

/// One primitive's triangles, decoded once per (mesh, primitive) so that a mesh used by many
/// nodes is decoded once; its vertices live in the rig as primitive `id`.
struct LocalPrimitive {
    id: u32,
    triangles: Vec<[u32; 3]>,
}

impl Loader<'_> {
    fn load(&self, roots: &[usize], plan: crate::load_budget::Plan) -> Result<Loaded, SceneError> {
        let mut report = LoadReport { source: self.name.clone(), ..Default::default() };
        let mut rig = RigBuilder::new(self.doc, self.buffers, &self.name);
        // Decode every mesh once, in document order.
        let mut meshes: Vec<Vec<Option<LocalPrimitive>>> = Vec::new();
        for mesh in self.doc.meshes() {
            let mut prims = Vec::new();
            for prim in mesh.primitives() {
                report.primitives += 1;
                let at = PrimitiveRef {
                    mesh: mesh.index(),
                    mesh_name: mesh.name().map(str::to_string),
                    primitive: prim.index(),
                };
                prims.push(self.decode_primitive(&prim, at, &mut report, &mut rig)?);
            }
            meshes.push(prims);
        }
        report.meshes = meshes.len();

        // The budget was checked: reserve the flattened mesh once, and turn an allocator refusal
        // (an address-space limit) into an error rather than an abort.
        let mut out = Mesh::default();
        let reserve = |what: &'static str, e: std::collections::TryReserveError| SceneError::OverBudget {
            source_name: self.name.clone(),
            detail: format!("cannot allocate the flattened mesh's {what}: {e}"),
            flag: "--max-load-bytes",
        };
        out.positions.try_reserve_exact(plan.vertices as usize).map_err(|e| reserve("vertices", e))?;
        out.indices.try_reserve_exact(plan.triangles as usize).map_err(|e| reserve("triangles", e))?;
        let nodes: Vec<gltf::Node> = self.doc.nodes().collect();
        let mut walk = SceneWalk {
            meshes: &meshes,
            visit_below: &plan.visit_below,
            instancing: &plan.instancing,
            out: &mut out,
            path: Vec::new(),
            rig: &mut rig,
        };
        for &root in roots {
            if plan.visit_below[root] {
                self.visit(&nodes[root], None, &mut walk)?;
            }
        }
        let rig = rig.finish()?;
        rig.pose(None, &mut PoseScratch::default(), &mut out.positions)?;
        if out.indices.is_empty() {
            let detail = if report.skipped_primitives.is_empty() {
                String::new()
            } else {
                format!(" (skipped: {})", report.skipped_primitives.join("; "))
            };
            return Err(SceneError::NoTriangles { source_name: self.name.clone(), detail });
        }
        let base = LoadReport::for_mesh(&self.name, &out);
        report.triangles = base.triangles;
        report.vertices = base.vertices;
        report.bounds_min = base.bounds_min;
        report.bounds_max = base.bounds_max;
        report.degenerate_triangles = base.degenerate_triangles;
        report.animation = rig.summary_if_any();
        Ok(Loaded { mesh: out, rig, report })
    }

    /// Visits `node` under the visit `parent`: its mesh's primitives become instances (and
    /// triangles, in order), then its children that lead to a mesh or a joint.
    fn visit(&self, node: &gltf::Node, parent: Option<u32>, walk: &mut SceneWalk) -> Result<(), SceneError> {
        let SceneWalk { meshes, visit_below, instancing, out, path, rig } = walk;
        let idx = node.index();
        if path.contains(&idx) {
            return Err(SceneError::InvalidNode {
                source_name: self.name.clone(),
                node: idx,
                detail: format!("is its own ancestor (cycle through nodes {path:?})"),
            });
        }
        if path.len() >= MAX_NODE_DEPTH {
            return Err(SceneError::InvalidNode {
                source_name: self.name.clone(),
                node: idx,
                detail: format!("hierarchy deeper than {MAX_NODE_DEPTH} levels"),
            });
        }
        let visit = rig.visit(idx, parent);
        if let Some(mesh) = node.mesh() {
            // EXT_mesh_gpu_instancing: the primitives once per instance, instance after instance
            // (the instances' matrices read at the node's first visit).
            let (first, count) = match &instancing[idx] {
                Some(gpu) => {
                    let r = rig.placements(idx, || gpu.matrices(self.doc, self.buffers, idx, &self.name))?;
                    (Some(r.start), r.len())
                }
                None => (None, 1),
            };
            for k in 0..count as u32 {
                let placement = first.map(|s| s + k);
                for prim in meshes[mesh.index()].iter().flatten() {
                    let total = out.indices.len() as u64 + prim.triangles.len() as u64;
                    if total > MAX_TRIANGLES {
                        return Err(SceneError::TooLarge {
                            source_name: self.name.clone(),
                            what: "triangle count after instancing",
                            count: total,
                            limit: MAX_TRIANGLES,
                        });
                    }
                    let base = rig.instance(visit, idx, prim.id, placement);
                    out.indices.extend(prim.triangles.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
                }
            }
        }
        path.push(idx);
        for child in node.children().filter(|c| visit_below[c.index()]) {
            self.visit(&child, Some(visit), walk)?;
        }
        walk.path.pop();
        Ok(())
    }

    fn decode_primitive(
        &self,
        prim: &gltf::Primitive,
        at: PrimitiveRef,
        report: &mut LoadReport,
        rig: &mut RigBuilder,
    ) -> Result<Option<LocalPrimitive>, SceneError> {
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            report.skipped_primitives.push(format!("{at}: mode {mode:?} is not a triangle mode"));
            return Ok(None);
        }
        let Some(pos) = prim.get(&gltf::Semantic::Positions) else {
            return Err(SceneError::MissingPositions { source_name: self.name.clone(), at });
        };
        // Float positions, or under KHR_mesh_quantization 8- and 16-bit integers (normalized or
        // not), whose values the accessor rules decode and the node transforms dequantize.
        let float = pos.data_type() == DataType::F32 && !pos.normalized();
        let quantized =
            matches!(pos.data_type(), DataType::I8 | DataType::U8 | DataType::I16 | DataType::U16) && self.quantized;
        if !(float || quantized) || pos.dimensions() != Dimensions::Vec3 {
            return Err(SceneError::NonFloatPositions {
                source_name: self.name.clone(),
                at,
                accessor: pos.index(),
                found: format!(
                    "{:?} {:?}{}",
                    pos.data_type(),
                    pos.dimensions(),
                    if pos.normalized() { " normalized" } else { "" }
                ),
            });
        }
        let positions = self.read_positions(&pos, &at)?;
        for (i, p) in positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(SceneError::NonFiniteVertex {
                    source_name: self.name.clone(),
                    at,
                    node: None,
                    vertex: i,
                    value: p.to_array(),
                });
            }
        }
        let indices: Vec<u32> = match prim.indices() {
            Some(acc) => self.read_indices(&acc, &at)?,
            None => {
                if positions.len() as u64 > u32::MAX as u64 {
                    return Err(self.too_large("vertex count", positions.len() as u64, u32::MAX as u64));
                }
                (0..positions.len() as u32).collect()
            }
        };
        for (i, &ix) in indices.iter().enumerate() {
            if ix as usize >= positions.len() {
                return Err(SceneError::IndexOutOfRange {
                    source_name: self.name.clone(),
                    at,
                    index_position: i,
                    index: ix,
                    vertex_count: positions.len(),
                });
            }
        }
        let triangles = assemble(mode, &indices);
        if triangles.is_empty() {
            report.skipped_primitives.push(format!("{at}: {} indices make no triangle", indices.len()));
            return Ok(None);
        }
        let skinned = rig.mesh_is_skinned(at.mesh);
        let id = rig.primitive(prim, at, positions, skinned)?;
        Ok(Some(LocalPrimitive { id, triangles }))
    }

    fn too_large(&self, what: &'static str, count: u64, limit: u64) -> SceneError {
        SceneError::TooLarge { source_name: self.name.clone(), what, count, limit }
    }

    /// Turns an [`AccessorFault`] into the error naming this accessor.
    fn fault(&self, f: AccessorFault, ctx: AccessorCtx<'_>) -> SceneError {
        let AccessorCtx { at, accessor, semantic } = ctx;
        let (source_name, at) = (self.name.clone(), at.clone());
        match f {
            AccessorFault::OutOfBounds(detail) => {
                SceneError::AccessorOutOfBounds { source_name, at, accessor, semantic, detail }
            }
            AccessorFault::Invalid(detail) => {
                SceneError::InvalidAccessor { source_name, at, accessor, semantic, detail }
            }
        }
    }

    fn read_positions(&self, acc: &gltf::Accessor, at: &PrimitiveRef) -> Result<Vec<Vec3>, SceneError> {
        let ctx = AccessorCtx { at, accessor: acc.index(), semantic: "POSITION" };
        let c = read_components(self.buffers, acc).map_err(|f| self.fault(f, ctx))?;
        Ok(c.chunks_exact(3).map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)).collect())
    }

    fn read_indices(&self, acc: &gltf::Accessor, at: &PrimitiveRef) -> Result<Vec<u32>, SceneError> {
        let invalid = |detail: String| SceneError::InvalidAccessor {
            source_name: self.name.clone(),
            at: at.clone(),
            accessor: acc.index(),
            semantic: "indices",
            detail,
        };
        let size = match acc.data_type() {
            DataType::U8 => 1,
            DataType::U16 => 2,
            DataType::U32 => 4,
            other => return Err(invalid(format!("component type {other:?}; indices must be unsigned integers"))),
        };
        if acc.dimensions() != Dimensions::Scalar || acc.sparse().is_some() {
            return Err(invalid(format!(
                "type {:?}{}; indices must be a non-sparse SCALAR accessor",
                acc.dimensions(),
                if acc.sparse().is_some() { " (sparse)" } else { "" }
            )));
        }
        let count = acc.count();
        let Some(view) = acc.view() else {
            return Ok(vec![0; count]);
        };
        let ctx = AccessorCtx { at, accessor: acc.index(), semantic: "indices" };
        let (bytes, stride) =
            view_bytes(self.buffers, &view, acc.offset(), count, size).map_err(|f| self.fault(f, ctx))?;
        Ok((0..count).map(|i| read_uint(&bytes[i * stride..], size)).collect())
    }
}

/// Which accessor a byte range belongs to, for error messages.
#[derive(Clone, Copy)]
struct AccessorCtx<'a> {
    at: &'a PrimitiveRef,
    accessor: usize,
    semantic: &'static str,
}

/// Turns an index sequence into triangles following the glTF rules for each mode (see the
/// module doc for the exact order).
pub fn assemble(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::Triangles => idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
            .map(|i| if i % 2 == 0 { [idx[i], idx[i + 1], idx[i + 2]] } else { [idx[i + 1], idx[i], idx[i + 2]] })
            .collect(),
        Mode::TriangleFan => (0..idx.len().saturating_sub(2)).map(|i| [idx[i + 1], idx[i + 2], idx[0]]).collect(),
        _ => Vec::new(),
    }
}
