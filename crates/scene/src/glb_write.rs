//! Writes a [`Mesh`] as a minimal binary glTF 2.0 file (`.glb`): one node, one mesh, one
//! indexed `TRIANGLES` primitive with float positions and `u32` indices. Loading it back gives
//! the same triangles in the same order.

use crate::mesh::Mesh;

/// Encodes `mesh` as `.glb` bytes. `generator` goes into `asset.generator`.
pub fn to_glb(mesh: &Mesh, generator: &str) -> Vec<u8> {
    let mut bin = Vec::with_capacity(mesh.positions.len() * 12 + mesh.indices.len() * 12);
    for p in &mesh.positions {
        bin.extend_from_slice(bytemuck::bytes_of(&p.to_array()));
    }
    let pos_len = bin.len();
    for t in &mesh.indices {
        bin.extend_from_slice(bytemuck::bytes_of(t));
    }
    let idx_len = bin.len() - pos_len;
    // Positions accessors must carry min/max (glTF spec).
    let b = mesh.bounds();
    let (min, max) = if b.is_empty() { ([0.0; 3], [0.0; 3]) } else { (b.min.to_array(), b.max.to_array()) };
    let json = serde_json::json!({
        "asset": { "version": "2.0", "generator": generator },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "mode": 4 }] }],
        "buffers": [{ "byteLength": bin.len() }],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": pos_len, "target": 34962 },
            { "buffer": 0, "byteOffset": pos_len, "byteLength": idx_len, "target": 34963 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": mesh.positions.len(), "type": "VEC3",
              "min": min, "max": max },
            { "bufferView": 1, "componentType": 5125, "count": mesh.indices.len() * 3, "type": "SCALAR" }
        ]
    });
    let mut json = serde_json::to_vec(&json).expect("JSON of plain values always serialises");
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    assemble_glb(&json, Some(&bin))
}

/// Packs a JSON chunk (already padded to 4 bytes) and an optional BIN chunk into a `.glb`.
/// Public so tests can build malformed files around valid framing.
pub fn assemble_glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let total = 12 + 8 + json.len() + bin.map_or(0, |b| 8 + b.len());
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json);
    if let Some(bin) = bin {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
    }
    out
}
