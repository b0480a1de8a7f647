//! Builds glTF documents in test code: a JSON value plus one binary buffer, written as .glb or
//! as .gltf with a data URI or an external .bin.

use serde_json::{Value, json};

/// A glTF document under construction.
pub struct Doc {
    pub json: Value,
    pub bin: Vec<u8>,
}

impl Doc {
    pub fn new() -> Doc {
        Doc {
            json: json!({
                "asset": {"version": "2.0"},
                "buffers": [], "bufferViews": [], "accessors": [], "meshes": [], "nodes": [],
                "scenes": [{"nodes": []}], "scene": 0
            }),
            bin: Vec::new(),
        }
    }

    pub fn push(&mut self, key: &str, v: Value) -> usize {
        let arr = self.json[key].as_array_mut().unwrap();
        arr.push(v);
        arr.len() - 1
    }

    /// Appends raw bytes as a buffer view; returns its index.
    pub fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let off = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.push("bufferViews", json!({"buffer": 0, "byteOffset": off, "byteLength": bytes.len()}))
    }

    /// An accessor over new bytes (used by tests/hostile.rs): `component_type` (5121 u8, 5123 u16, 5125 u32, 5126 f32),
    /// `count` elements of type `ty` ("SCALAR", "VEC3", "MAT4", …).
    #[allow(dead_code)]
    pub fn accessor(&mut self, bytes: &[u8], component_type: u32, count: usize, ty: &str) -> usize {
        let v = self.view(bytes);
        self.push("accessors", json!({"bufferView": v, "componentType": component_type, "count": count, "type": ty}))
    }

    /// A float accessor: `values.len() / components` elements of type `ty`.
    #[allow(dead_code)]
    pub fn floats(&mut self, values: &[f32], ty: &str, components: usize) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.accessor(&bytes, 5126, values.len() / components, ty)
    }

    pub fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = p.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let v = self.view(&bytes);
        self.push("accessors", json!({"bufferView": v, "componentType": 5126, "count": p.len(), "type": "VEC3"}))
    }

    pub fn indices_u16(&mut self, idx: &[u16]) -> usize {
        let bytes: Vec<u8> = idx.iter().flat_map(|x| x.to_le_bytes()).collect();
        let v = self.view(&bytes);
        self.push("accessors", json!({"bufferView": v, "componentType": 5123, "count": idx.len(), "type": "SCALAR"}))
    }

    pub fn indices_u32(&mut self, idx: &[u32]) -> usize {
        let bytes: Vec<u8> = idx.iter().flat_map(|x| x.to_le_bytes()).collect();
        let v = self.view(&bytes);
        self.push("accessors", json!({"bufferView": v, "componentType": 5125, "count": idx.len(), "type": "SCALAR"}))
    }

    /// A mesh with one primitive; returns the mesh index.
    pub fn mesh(&mut self, pos: usize, indices: Option<usize>, mode: u32) -> usize {
        let mut prim = json!({"attributes": {"POSITION": pos}, "mode": mode});
        if let Some(i) = indices {
            prim["indices"] = json!(i);
        }
        self.push("meshes", json!({"primitives": [prim]}))
    }

    pub fn node(&mut self, v: Value) -> usize {
        self.push("nodes", v)
    }

    pub fn root(&mut self, node: usize) {
        self.json["scenes"][0]["nodes"].as_array_mut().unwrap().push(json!(node));
    }

    /// One triangle mesh placed at the root: the smallest valid scene.
    pub fn single_triangle() -> Doc {
        let mut d = Doc::new();
        let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let i = d.indices_u16(&[0, 1, 2]);
        let m = d.mesh(p, Some(i), 4);
        let n = d.node(json!({"mesh": m}));
        d.root(n);
        d
    }

    fn finish_buffers(&mut self, uri: Option<String>) {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut b = json!({"byteLength": self.bin.len()});
        if let Some(u) = uri {
            b["uri"] = json!(u);
        }
        self.json["buffers"] = json!([b]);
    }

    pub fn glb(mut self) -> Vec<u8> {
        self.finish_buffers(None);
        let mut j = serde_json::to_vec(&self.json).unwrap();
        while !j.len().is_multiple_of(4) {
            j.push(b' ');
        }
        gridrt_scene::glb_write::assemble_glb(&j, Some(&self.bin))
    }

    /// `.gltf` JSON with the buffer embedded as a base64 data URI.
    pub fn gltf_embedded(mut self) -> Vec<u8> {
        let uri = format!("data:application/octet-stream;base64,{}", base64(&self.bin));
        self.finish_buffers(Some(uri));
        serde_json::to_vec(&self.json).unwrap()
    }

    /// `.gltf` JSON referencing `bin_name`; returns (json, bin bytes).
    pub fn gltf_external(mut self, bin_name: &str) -> (Vec<u8>, Vec<u8>) {
        self.finish_buffers(Some(bin_name.to_string()));
        (serde_json::to_vec(&self.json).unwrap(), self.bin)
    }
}

pub fn base64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            if i <= c.len() {
                s.push(T[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A fresh temporary directory for file-based cases, removed when the value is dropped.
pub fn temp_dir(tag: &str) -> tempfile::TempDir {
    tempfile::Builder::new().prefix(&format!("gridrt-scene-test-{tag}-")).tempdir().unwrap()
}
