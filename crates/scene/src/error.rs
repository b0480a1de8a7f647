//! Typed errors for everything that reads scene and ray files.
//!
//! Every variant names the file (`source`) and, where it applies, the mesh, primitive, accessor
//! or vertex at fault, so a user can find the problem without a debugger.

use thiserror::Error;

/// Where in a glTF document a problem sits: `mesh 3 "Body", primitive 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct PrimitiveRef {
    pub mesh: usize,
    pub mesh_name: Option<String>,
    pub primitive: usize,
}

impl std::fmt::Display for PrimitiveRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.mesh_name {
            Some(n) => write!(f, "mesh {} \"{}\", primitive {}", self.mesh, n, self.primitive),
            None => write!(f, "mesh {}, primitive {}", self.mesh, self.primitive),
        }
    }
}

#[derive(Debug, Error)]
pub enum SceneError {
    #[error("{source_name}: cannot read file: {err}")]
    Io {
        source_name: String,
        #[source]
        err: std::io::Error,
    },
    #[error("{source_name}: not a glTF file (neither a .glb binary nor JSON): {detail}")]
    NotGltf { source_name: String, detail: String },
    #[error("{source_name}: truncated .glb: {detail}")]
    TruncatedGlb { source_name: String, detail: String },
    #[error("{source_name}: malformed .glb: {detail}")]
    InvalidGlb { source_name: String, detail: String },
    #[error("{source_name}: invalid glTF JSON: {detail}")]
    InvalidJson { source_name: String, detail: String },
    #[error("{source_name}: buffer {buffer}: {detail}")]
    Buffer { source_name: String, buffer: usize, detail: String },
    #[error("{source_name}: {at}: accessor {accessor} ({semantic}) out of bounds: {detail}")]
    AccessorOutOfBounds {
        source_name: String,
        at: PrimitiveRef,
        accessor: usize,
        semantic: &'static str,
        detail: String,
    },
    #[error("{source_name}: {at}: accessor {accessor} ({semantic}) is invalid: {detail}")]
    InvalidAccessor { source_name: String, at: PrimitiveRef, accessor: usize, semantic: &'static str, detail: String },
    #[error(
        "{source_name}: {at}: POSITION accessor {accessor} has {found} components; gridrt needs \
         32-bit float VEC3 positions (or 8- and 16-bit integer ones under KHR_mesh_quantization)"
    )]
    NonFloatPositions { source_name: String, at: PrimitiveRef, accessor: usize, found: String },
    #[error("{source_name}: {at}: has no POSITION attribute")]
    MissingPositions { source_name: String, at: PrimitiveRef },
    #[error(
        "{source_name}: {at}: index {index_position} is {index}, but the primitive has only \
         {vertex_count} vertices"
    )]
    IndexOutOfRange { source_name: String, at: PrimitiveRef, index_position: usize, index: u32, vertex_count: usize },
    #[error("{source_name}: {at}{}: vertex {vertex} is not finite: {value:?}", node.map(|n| format!(", node {n}")).unwrap_or_default())]
    NonFiniteVertex {
        source_name: String,
        at: PrimitiveRef,
        /// The node whose transform produced it; `None` when the file's own data is not finite.
        node: Option<usize>,
        vertex: usize,
        value: [f32; 3],
    },
    #[error(
        "{source_name}: {at}, node {node}: vertex {vertex} is {value:?}, beyond the supported \
         magnitude {limit:e}"
    )]
    CoordinateOutOfRange {
        source_name: String,
        at: PrimitiveRef,
        node: usize,
        vertex: usize,
        value: [f32; 3],
        limit: f32,
    },
    #[error("{source_name}: node {node}: {detail}")]
    InvalidNode { source_name: String, node: usize, detail: String },
    #[error("{source_name}: the scene has no triangles{detail}")]
    NoTriangles { source_name: String, detail: String },
    #[error("{source_name}: too large: {what} is {count}, the limit is {limit}")]
    TooLarge { source_name: String, what: &'static str, count: u64, limit: u64 },
    #[error("{source_name}: {detail}")]
    Unsupported { source_name: String, detail: String },
    /// Over a load limit ([`crate::gltf_load::LoadLimits`]); `flag` raises it.
    #[error("{source_name}: over the load limits: {detail} (raise it with {flag})")]
    OverBudget { source_name: String, detail: String, flag: &'static str },
    #[error("{source_name}: animation {animation}{}: {detail}", sampler.map(|s| format!(", sampler {s}")).unwrap_or_default())]
    InvalidAnimation { source_name: String, animation: usize, sampler: Option<usize>, detail: String },
    #[error("{source_name}: skin {skin}: {detail}")]
    InvalidSkin { source_name: String, skin: usize, detail: String },
    #[error("{source_name}: {at}: morph targets: {detail}")]
    InvalidMorphTargets { source_name: String, at: PrimitiveRef, detail: String },
    /// `--animation` named no clip of the file.
    #[error("{source_name}: no animation {key:?}; the file has {available}")]
    UnknownAnimation { source_name: String, key: String, available: String },
    /// Posing at a time produced a vertex the grid cannot hold (not finite, or beyond
    /// [`crate::gltf_load::MAX_COORDINATE`]).
    #[error("{inner} (animation {clip} at t = {seconds} s)")]
    AtTime { clip: usize, seconds: f64, inner: Box<SceneError> },
}

#[derive(Debug, Error)]
pub enum RayFileError {
    #[error("{source_name}: cannot read or write: {err}")]
    Io {
        source_name: String,
        #[source]
        err: std::io::Error,
    },
    #[error("{source_name}: not a regular file")]
    NotAFile { source_name: String },
    #[error("{source_name}: {len} bytes, more than the limit of {limit} bytes (a quarter of memory)")]
    TooLarge { source_name: String, len: u64, limit: u64 },
    #[error("{source_name}: size {len} bytes is not a multiple of {record} bytes (one {what} record)")]
    BadSize { source_name: String, len: u64, record: usize, what: &'static str },
}
