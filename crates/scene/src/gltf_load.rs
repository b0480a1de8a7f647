//! glTF 2.0 loading (`.gltf` with embedded or external buffers, and `.glb`) into one [`Mesh`].
//!
//! # Triangle order (public contract)
//! Hit files name triangles by index, so the order is fixed and documented:
//! 1. the nodes of the default scene (or scene 0 when none is marked default; or, in a file with
//!    no scenes, every root node in index order) are visited **depth-first in document order**:
//!    a node, then its children in the order of its `children` array;
//! 2. for each visited node with a mesh, that mesh's primitives in order;
//! 3. within a primitive, triangles in index order: `TRIANGLES` takes indices `3i, 3i+1, 3i+2`;
//!    `TRIANGLE_STRIP` triangle `i` is `(i, i+1, i+2)` for even `i` and `(i+1, i, i+2)` for odd
//!    `i` (the glTF winding rule); `TRIANGLE_FAN` triangle `i` is `(i+1, i+2, 0)`.
//!    Non-indexed primitives use the vertex order as the index sequence.
//!
//! Degenerate (zero-area) triangles are kept, so that indices stay aligned with the file; they
//! never produce a hit. Primitives of other modes (points, lines) are skipped and reported.
//!
//! # Robustness
//! Accessors are read here with explicit bounds checks rather than through the `gltf` crate's
//! readers, so that every malformed file gets a [`SceneError`] naming the mesh, primitive and
//! accessor at fault instead of a panic, and so that absurd element counts are rejected before
//! anything is allocated.

use std::path::Path;

use glam::{DMat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use crate::error::{PrimitiveRef, SceneError};
use crate::mesh::{LoadReport, Mesh};

/// Largest scene file read (also bounds external buffers).
pub const MAX_FILE_BYTES: u64 = 2 << 30;
/// Largest number of triangles in one flattened scene (indices must fit in `u32` with room for
/// the "no hit" marker `0xFFFF_FFFF`).
pub const MAX_TRIANGLES: u64 = 1 << 28;
/// Largest coordinate magnitude after transforms: keeps every extent and grid computation
/// finite in f32 (extents up to 2e30, products of cell counts far from overflow).
pub const MAX_COORDINATE: f32 = 1e30;
/// Largest node depth (guards against hierarchies crafted to exhaust the stack).
pub const MAX_NODE_DEPTH: usize = 256;

/// Loads a `.gltf` or `.glb` file; external buffers are resolved next to it.
pub fn load_path(path: &Path) -> Result<(Mesh, LoadReport), SceneError> {
    let name = path.display().to_string();
    let bytes = read_file_bounded(path, &name)?;
    load_slice(&bytes, &name, path.parent())
}

fn read_file_bounded(path: &Path, name: &str) -> Result<Vec<u8>, SceneError> {
    let io = |err| SceneError::Io { source_name: name.to_string(), err };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(SceneError::Io {
            source_name: name.to_string(),
            err: std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a regular file"),
        });
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(SceneError::TooLarge {
            source_name: name.to_string(),
            what: "file size in bytes",
            count: meta.len(),
            limit: MAX_FILE_BYTES,
        });
    }
    std::fs::read(path).map_err(io)
}

/// Loads glTF from memory. `source_name` is used in errors and the report; `base_dir` resolves
/// external buffer URIs (`None`: only embedded data and the GLB chunk are allowed).
pub fn load_slice(bytes: &[u8], source_name: &str, base_dir: Option<&Path>) -> Result<(Mesh, LoadReport), SceneError> {
    let name = source_name.to_string();
    precheck(bytes, &name)?;
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| map_gltf_error(e, &name))?;
    let doc = gltf.document;
    validate(&doc, &name)?;
    precheck_external_buffers(&doc, base_dir, &name)?;
    let buffers = gltf::import_buffers(&doc, base_dir, gltf.blob).map_err(|e| map_gltf_error(e, &name))?;
    let buffers: Vec<&[u8]> = buffers.iter().map(|d| &d.0[..]).collect();
    Loader { name, doc: &doc, buffers }.load()
}

/// Classifies the file before handing it to the `gltf` crate, so that the common failure
/// modes (not glTF at all, a cut-off download) get a precise message.
fn precheck(bytes: &[u8], name: &str) -> Result<(), SceneError> {
    if bytes.starts_with(b"glTF") {
        if bytes.len() < 12 {
            return Err(SceneError::TruncatedGlb {
                source_name: name.into(),
                detail: format!("{} bytes, shorter than the 12-byte header", bytes.len()),
            });
        }
        let word = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
        let version = word(4);
        if version != 2 {
            return Err(SceneError::Unsupported {
                source_name: name.into(),
                detail: format!("glb container version {version}; only glTF 2.0 is supported"),
            });
        }
        let declared = word(8) as usize;
        if declared > bytes.len() {
            return Err(SceneError::TruncatedGlb {
                source_name: name.into(),
                detail: format!("header declares {declared} bytes, file has {}", bytes.len()),
            });
        }
        // Walk the chunks: each must fit inside the declared length.
        let mut o = 12;
        let mut first = true;
        while o < declared {
            if o + 8 > declared {
                return Err(SceneError::TruncatedGlb {
                    source_name: name.into(),
                    detail: format!("chunk header at byte {o} is cut off"),
                });
            }
            let len = word(o) as usize;
            let kind = word(o + 4);
            if o + 8 + len > declared {
                return Err(SceneError::TruncatedGlb {
                    source_name: name.into(),
                    detail: format!("chunk at byte {o} declares {len} bytes, only {} remain", declared - o - 8),
                });
            }
            if first && kind != 0x4E4F_534A {
                return Err(SceneError::InvalidGlb {
                    source_name: name.into(),
                    detail: format!("first chunk has type 0x{kind:08X}, expected JSON"),
                });
            }
            first = false;
            o += 8 + len;
        }
        if first {
            return Err(SceneError::InvalidGlb { source_name: name.into(), detail: "no JSON chunk".into() });
        }
        return Ok(());
    }
    match bytes.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Ok(()),
        Some(_) if bytes.len() >= 4 => Err(SceneError::NotGltf {
            source_name: name.into(),
            detail: format!("starts with bytes {:02X?}", &bytes[..4]),
        }),
        _ => Err(SceneError::NotGltf {
            source_name: name.into(),
            detail: format!("{} bytes, no glTF header or JSON object", bytes.len()),
        }),
    }
}

/// The `gltf` crate's validation (every index reference in range, required fields present),
/// except that a POSITION accessor's missing `min`/`max` is tolerated: the spec requires them,
/// but many exporters omit them and gridrt computes bounds itself.
fn validate(doc: &gltf::Document, name: &str) -> Result<(), SceneError> {
    use gltf::json::validation::{Error, Validate};
    let root = doc.as_json();
    // gltf-json 1.4's validator indexes `accessors[POSITION]` unchecked and panics on a dangling
    // index: check those references first.
    for (mi, mesh) in root.meshes.iter().enumerate() {
        for (pi, prim) in mesh.primitives.iter().enumerate() {
            for (sem, acc) in &prim.attributes {
                if acc.value() >= root.accessors.len() {
                    return Err(SceneError::InvalidJson {
                        source_name: name.into(),
                        detail: format!(
                            "meshes[{mi}].primitives[{pi}].attributes[{sem:?}]: accessor {} does not exist ({} accessors)",
                            acc.value(),
                            root.accessors.len()
                        ),
                    });
                }
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, err| {
        let p = path().to_string();
        let min_max = p.ends_with(".min") || p.ends_with(".max");
        if !(min_max && matches!(err, Error::Missing)) {
            errors.push((p, err));
        }
    });
    if errors.is_empty() {
        return Ok(());
    }
    let detail = errors.iter().take(5).map(|(p, e)| format!("{p}: {e}")).collect::<Vec<_>>().join("; ");
    Err(SceneError::InvalidJson { source_name: name.into(), detail })
}

fn precheck_external_buffers(doc: &gltf::Document, base_dir: Option<&Path>, name: &str) -> Result<(), SceneError> {
    for buffer in doc.buffers() {
        if let gltf::buffer::Source::Uri(uri) = buffer.source() {
            if uri.starts_with("data:") {
                continue;
            }
            let Some(base) = base_dir else {
                return Err(SceneError::Buffer {
                    source_name: name.into(),
                    buffer: buffer.index(),
                    detail: format!("external file \"{uri}\" but no directory to resolve it in"),
                });
            };
            let path = base.join(uri);
            // A URI naming a device or directory would hang or fail obscurely inside the reader.
            match std::fs::metadata(&path) {
                Ok(m) if !m.is_file() => {
                    return Err(SceneError::Buffer {
                        source_name: name.into(),
                        buffer: buffer.index(),
                        detail: format!("\"{}\" is not a regular file", path.display()),
                    });
                }
                Ok(m) if m.len() > MAX_FILE_BYTES => {
                    return Err(SceneError::TooLarge {
                        source_name: name.into(),
                        what: "external buffer size in bytes",
                        count: m.len(),
                        limit: MAX_FILE_BYTES,
                    });
                }
                Ok(_) => {}
                Err(e) => {
                    return Err(SceneError::Buffer {
                        source_name: name.into(),
                        buffer: buffer.index(),
                        detail: format!("cannot open \"{}\": {e}", path.display()),
                    });
                }
            }
        }
    }
    Ok(())
}

fn map_gltf_error(e: gltf::Error, name: &str) -> SceneError {
    let name = name.to_string();
    match e {
        gltf::Error::Binary(b) => SceneError::InvalidGlb { source_name: name, detail: b.to_string() },
        gltf::Error::Deserialize(j) => SceneError::InvalidJson { source_name: name, detail: j.to_string() },
        gltf::Error::Validation(list) => {
            let detail = list.iter().take(5).map(|(path, err)| format!("{path}: {err}")).collect::<Vec<_>>().join("; ");
            SceneError::InvalidJson { source_name: name, detail }
        }
        gltf::Error::BufferLength { buffer, expected, actual } => SceneError::Buffer {
            source_name: name,
            buffer,
            detail: format!("declares {expected} bytes but only {actual} are available"),
        },
        gltf::Error::MissingBlob => SceneError::Buffer {
            source_name: name,
            buffer: 0,
            detail: "refers to the .glb BIN chunk, which is missing".into(),
        },
        gltf::Error::Base64(err) => {
            SceneError::Buffer { source_name: name, buffer: 0, detail: format!("bad base64 data URI: {err}") }
        }
        gltf::Error::Io(err) => SceneError::Io { source_name: name, err },
        other => SceneError::Unsupported { source_name: name, detail: other.to_string() },
    }
}

struct Loader<'a> {
    name: String,
    doc: &'a gltf::Document,
    buffers: Vec<&'a [u8]>,
}

/// One primitive's triangles in local space, cached per (mesh, primitive) so that a mesh used by
/// many nodes is decoded once.
struct LocalPrimitive {
    at: PrimitiveRef,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl Loader<'_> {
    fn load(&self) -> Result<(Mesh, LoadReport), SceneError> {
        let roots: Vec<gltf::Node> = match self.doc.default_scene().or_else(|| self.doc.scenes().next()) {
            Some(scene) => scene.nodes().collect(),
            None => {
                let mut is_child = vec![false; self.doc.nodes().len()];
                for n in self.doc.nodes() {
                    for c in n.children() {
                        is_child[c.index()] = true;
                    }
                }
                self.doc.nodes().filter(|n| !is_child[n.index()]).collect()
            }
        };

        let mut report = LoadReport { source: self.name.clone(), ..Default::default() };
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
                prims.push(self.decode_primitive(&prim, at, &mut report)?);
            }
            meshes.push(prims);
        }
        report.meshes = meshes.len();

        let mut out = Mesh::default();
        let mut path = Vec::new();
        for root in roots {
            self.visit(&root, DMat4::IDENTITY, &meshes, &mut out, &mut path)?;
        }
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
        Ok((out, report))
    }

    fn visit(
        &self,
        node: &gltf::Node,
        parent: DMat4,
        meshes: &[Vec<Option<LocalPrimitive>>],
        out: &mut Mesh,
        path: &mut Vec<usize>,
    ) -> Result<(), SceneError> {
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
        let local = glam::Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
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
                let base = out.positions.len() as u32;
                for (vi, p) in prim.positions.iter().enumerate() {
                    let w = world.transform_point3(p.as_dvec3()).as_vec3();
                    if !w.is_finite() {
                        return Err(SceneError::NonFiniteVertex {
                            source_name: self.name.clone(),
                            at: prim.at.clone(),
                            node: Some(idx),
                            vertex: vi,
                            value: w.to_array(),
                        });
                    }
                    if w.abs().max_element() > MAX_COORDINATE {
                        return Err(SceneError::CoordinateOutOfRange {
                            source_name: self.name.clone(),
                            at: prim.at.clone(),
                            node: idx,
                            vertex: vi,
                            value: w.to_array(),
                            limit: MAX_COORDINATE,
                        });
                    }
                    out.positions.push(w);
                }
                out.indices.extend(prim.triangles.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
            }
        }
        path.push(idx);
        for child in node.children() {
            self.visit(&child, world, meshes, out, path)?;
        }
        path.pop();
        Ok(())
    }

    fn decode_primitive(
        &self,
        prim: &gltf::Primitive,
        at: PrimitiveRef,
        report: &mut LoadReport,
    ) -> Result<Option<LocalPrimitive>, SceneError> {
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            report.skipped_primitives.push(format!("{at}: mode {mode:?} is not a triangle mode"));
            return Ok(None);
        }
        let Some(pos) = prim.get(&gltf::Semantic::Positions) else {
            return Err(SceneError::MissingPositions { source_name: self.name.clone(), at });
        };
        if pos.data_type() != DataType::F32 || pos.dimensions() != Dimensions::Vec3 || pos.normalized() {
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
        Ok(Some(LocalPrimitive { at, positions, triangles }))
    }

    fn too_large(&self, what: &'static str, count: u64, limit: u64) -> SceneError {
        SceneError::TooLarge { source_name: self.name.clone(), what, count, limit }
    }

    /// Bounds-checked view of `count` elements of `elem` bytes at `offset` in `view`.
    /// Returns the byte slice and the stride.
    fn element_bytes(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        count: usize,
        elem: usize,
        ctx: AccessorCtx<'_>,
    ) -> Result<(&[u8], usize), SceneError> {
        let AccessorCtx { at, accessor, semantic } = ctx;
        let oob = |detail: String| SceneError::AccessorOutOfBounds {
            source_name: self.name.clone(),
            at: at.clone(),
            accessor,
            semantic,
            detail,
        };
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(SceneError::InvalidAccessor {
                source_name: self.name.clone(),
                at: at.clone(),
                accessor,
                semantic,
                detail: format!("byteStride {stride} is smaller than the element size {elem}"),
            });
        }
        let buffer = view.buffer().index();
        let data = self.buffers.get(buffer).copied().ok_or_else(|| oob(format!("buffer {buffer} missing")))?;
        let view_end = view.offset().checked_add(view.length());
        if view_end.is_none_or(|e| e > data.len()) {
            return Err(oob(format!(
                "buffer view {} spans bytes {}..{} of a {}-byte buffer",
                view.index(),
                view.offset(),
                view.offset() as u128 + view.length() as u128,
                data.len()
            )));
        }
        let view_bytes = &data[view.offset()..view.offset() + view.length()];
        if count == 0 {
            return Ok((&[], stride));
        }
        // u128: a crafted count can overflow u64 arithmetic on 32-bit targets.
        let need = offset as u128 + stride as u128 * (count as u128 - 1) + elem as u128;
        if need > view_bytes.len() as u128 {
            return Err(oob(format!(
                "{count} elements of {elem} bytes (stride {stride}, offset {offset}) need {need} \
                 bytes, buffer view {} has {}",
                view.index(),
                view_bytes.len()
            )));
        }
        Ok((&view_bytes[offset..need as usize], stride))
    }

    fn read_positions(&self, acc: &gltf::Accessor, at: &PrimitiveRef) -> Result<Vec<Vec3>, SceneError> {
        let count = acc.count();
        if count as u64 > MAX_TRIANGLES * 3 {
            return Err(self.too_large("POSITION count", count as u64, MAX_TRIANGLES * 3));
        }
        let read3 = |b: &[u8]| {
            Vec3::new(
                f32::from_le_bytes(b[0..4].try_into().unwrap()),
                f32::from_le_bytes(b[4..8].try_into().unwrap()),
                f32::from_le_bytes(b[8..12].try_into().unwrap()),
            )
        };
        let mut out = match acc.view() {
            Some(view) => {
                let (bytes, stride) = self.element_bytes(
                    &view,
                    acc.offset(),
                    count,
                    12,
                    AccessorCtx { at, accessor: acc.index(), semantic: "POSITION" },
                )?;
                (0..count).map(|i| read3(&bytes[i * stride..])).collect()
            }
            // No buffer view: the spec says the data is all zeros (sparse may replace some).
            None => vec![Vec3::ZERO; count],
        };
        if let Some(sparse) = acc.sparse() {
            let n = sparse.count();
            if n > count {
                return Err(SceneError::InvalidAccessor {
                    source_name: self.name.clone(),
                    at: at.clone(),
                    accessor: acc.index(),
                    semantic: "POSITION",
                    detail: format!("sparse count {n} exceeds the accessor count {count}"),
                });
            }
            let idx_info = sparse.indices();
            let isize = match idx_info.index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let (ib, _) = self.element_bytes(
                &idx_info.view(),
                idx_info.offset(),
                n,
                isize,
                AccessorCtx { at, accessor: acc.index(), semantic: "POSITION sparse indices" },
            )?;
            let vals = sparse.values();
            let (vb, _) = self.element_bytes(
                &vals.view(),
                vals.offset(),
                n,
                12,
                AccessorCtx { at, accessor: acc.index(), semantic: "POSITION sparse values" },
            )?;
            for k in 0..n {
                let target = read_uint(&ib[k * isize..], isize) as usize;
                if target >= count {
                    return Err(SceneError::InvalidAccessor {
                        source_name: self.name.clone(),
                        at: at.clone(),
                        accessor: acc.index(),
                        semantic: "POSITION",
                        detail: format!("sparse index {k} is {target}, accessor count is {count}"),
                    });
                }
                out[target] = read3(&vb[k * 12..]);
            }
        }
        Ok(out)
    }

    fn read_indices(&self, acc: &gltf::Accessor, at: &PrimitiveRef) -> Result<Vec<u32>, SceneError> {
        let size = match acc.data_type() {
            DataType::U8 => 1,
            DataType::U16 => 2,
            DataType::U32 => 4,
            other => {
                return Err(SceneError::InvalidAccessor {
                    source_name: self.name.clone(),
                    at: at.clone(),
                    accessor: acc.index(),
                    semantic: "indices",
                    detail: format!("component type {other:?}; indices must be unsigned integers"),
                });
            }
        };
        if acc.dimensions() != Dimensions::Scalar || acc.sparse().is_some() {
            return Err(SceneError::InvalidAccessor {
                source_name: self.name.clone(),
                at: at.clone(),
                accessor: acc.index(),
                semantic: "indices",
                detail: format!(
                    "type {:?}{}; indices must be a non-sparse SCALAR accessor",
                    acc.dimensions(),
                    if acc.sparse().is_some() { " (sparse)" } else { "" }
                ),
            });
        }
        let count = acc.count();
        if count as u64 > MAX_TRIANGLES * 3 {
            return Err(self.too_large("index count", count as u64, MAX_TRIANGLES * 3));
        }
        let Some(view) = acc.view() else {
            return Ok(vec![0; count]);
        };
        let (bytes, stride) = self.element_bytes(
            &view,
            acc.offset(),
            count,
            size,
            AccessorCtx { at, accessor: acc.index(), semantic: "indices" },
        )?;
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

fn read_uint(b: &[u8], size: usize) -> u32 {
    match size {
        1 => b[0] as u32,
        2 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
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
