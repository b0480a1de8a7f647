//! The file around a glTF document: its size, the `.glb` container, the JSON's validation,
//! and where buffer URIs may point. Everything here runs before a buffer is read, so a file
//! that is not glTF, is cut off, or names data outside its own folder gets a precise error.

use std::path::{Path, PathBuf};

use crate::error::SceneError;
use crate::file_read::{ReadFault, read_regular_file};
use crate::load_budget::LoadLimits;

/// Required extensions that leave geometry as plain accessors (materials, textures, lights).
const GEOMETRY_NEUTRAL_EXTENSIONS: &[&str] = &[
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_materials_unlit",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_variants",
    "KHR_texture_transform",
    "KHR_texture_basisu",
    "EXT_texture_webp",
    "KHR_lights_punctual",
];

/// Largest scene file read (also bounds external buffers).
pub const MAX_FILE_BYTES: u64 = 2 << 30;

/// The bytes of the scene file `path`, within [`MAX_FILE_BYTES`] and the byte budget.
pub(crate) fn read_file_bounded(path: &Path, name: &str, limits: &LoadLimits) -> Result<Vec<u8>, SceneError> {
    let limit = MAX_FILE_BYTES.min(limits.max_bytes);
    let source_name = name.to_string();
    read_regular_file(path, limit).map_err(|fault| match fault {
        ReadFault::Io(err) => SceneError::Io { source_name, err },
        ReadFault::NotAFile => SceneError::Io {
            source_name,
            err: std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a regular file"),
        },
        ReadFault::TooLarge { len } => {
            SceneError::TooLarge { source_name, what: "file size in bytes", count: len, limit }
        }
    })
}

/// Classifies the file before handing it to the `gltf` crate, so that the common failure
/// modes (not glTF at all, a cut-off download) get a precise message.
pub(crate) fn precheck(bytes: &[u8], name: &str) -> Result<(), SceneError> {
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
pub(crate) fn validate(doc: &gltf::Document, name: &str) -> Result<(), SceneError> {
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
    // Extensions a file requires change how its geometry is stored (compression, quantization,
    // instancing); gridrt reads plain accessors, quantized positions and instances, so say which
    // other one it is instead of failing obscurely.
    let decoded = |e: &str| {
        GEOMETRY_NEUTRAL_EXTENSIONS.contains(&e)
            || e == crate::gltf_load::MESH_QUANTIZATION
            || e == crate::instancing::MESH_GPU_INSTANCING
    };
    if let Some(ext) = root.extensions_required.iter().find(|e| !decoded(e)) {
        return Err(SceneError::Unsupported {
            source_name: name.into(),
            detail: format!(
                "the file requires the extension {ext}, which gridrt does not decode (plain accessors only)"
            ),
        });
    }
    // Nor does it check animation channels' targets (`Animation::validate` skips them), whose
    // accessors unwrap.
    for (ai, anim) in root.animations.iter().enumerate() {
        for (ci, ch) in anim.channels.iter().enumerate() {
            let at = format!("animations[{ai}].channels[{ci}].target");
            if ch.target.node.value() >= root.nodes.len() {
                return Err(SceneError::InvalidJson {
                    source_name: name.into(),
                    detail: format!(
                        "{at}.node: node {} does not exist ({} nodes)",
                        ch.target.node.value(),
                        root.nodes.len()
                    ),
                });
            }
            if !matches!(ch.target.path, gltf::json::validation::Checked::Valid(_)) {
                return Err(SceneError::InvalidJson {
                    source_name: name.into(),
                    detail: format!("{at}.path: not a glTF path"),
                });
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, err| {
        let p = path().to_string();
        let min_max = p.ends_with(".min") || p.ends_with(".max");
        // Required extensions were judged above (geometry-neutral ones are fine).
        let required = p.starts_with("extensionsRequired");
        let tolerated = required || (min_max && matches!(err, Error::Missing));
        if !tolerated {
            errors.push((p, err));
        }
    });
    if errors.is_empty() {
        return Ok(());
    }
    let detail = errors.iter().take(5).map(|(p, e)| format!("{p}: {e}")).collect::<Vec<_>>().join("; ");
    Err(SceneError::InvalidJson { source_name: name.into(), detail })
}

/// Where an external buffer's `uri` points, by the glTF rule that URIs are relative references:
/// `data:` URIs are embedded; anything else must be a relative path (percent-encoded, UTF-8)
/// that stays inside the glTF file's folder. Absolute paths, other schemes (`file:`, `http:`,
/// a drive letter) and `..` components are refused.
#[derive(Debug, PartialEq, Eq)]
pub enum BufferUri {
    Data,
    Relative(PathBuf),
}

/// Classifies `uri` by [`BufferUri`]'s rule; the error says why it is refused.
pub fn classify_uri(uri: &str) -> Result<BufferUri, String> {
    if uri.starts_with("data:") {
        return Ok(BufferUri::Data);
    }
    if let Some(colon) = uri.find(':') {
        let scheme = &uri[..colon];
        return Err(format!(
            "URI \"{uri}\" has the scheme or drive \"{scheme}:\"; only data: URIs and paths relative to the glTF file are read"
        ));
    }
    let decoded = percent_decode(uri).ok_or_else(|| format!("URI \"{uri}\" is not valid percent-encoded UTF-8"))?;
    if decoded.is_empty() {
        return Err("empty URI".into());
    }
    if decoded.starts_with('/') || decoded.starts_with('\\') {
        return Err(format!("URI \"{uri}\" is an absolute path; glTF URIs are relative to the file"));
    }
    let parts: Vec<&str> = decoded.split(['/', '\\']).collect();
    if parts.contains(&"..") {
        return Err(format!("URI \"{uri}\" leaves the glTF file's folder (a \"..\" component)"));
    }
    if decoded.contains('\0') {
        return Err(format!("URI \"{uri}\" contains a NUL character"));
    }
    Ok(BufferUri::Relative(parts.iter().filter(|p| !p.is_empty() && **p != ".").collect()))
}

/// `%XX` decoding to UTF-8; `None` for a bad escape or invalid UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Checks every external buffer before the `gltf` crate reads it: the URI rule above, a
/// folder to resolve it in, a regular file of bounded size.
pub(crate) fn precheck_external_buffers(
    doc: &gltf::Document,
    base_dir: Option<&Path>,
    name: &str,
) -> Result<(), SceneError> {
    for buffer in doc.buffers() {
        let gltf::buffer::Source::Uri(uri) = buffer.source() else { continue };
        let refuse = |detail: String| SceneError::Buffer { source_name: name.into(), buffer: buffer.index(), detail };
        let relative = match classify_uri(uri).map_err(refuse)? {
            BufferUri::Data => continue,
            BufferUri::Relative(p) => p,
        };
        let Some(base) = base_dir else {
            return Err(refuse(format!("external file \"{uri}\" but no directory to resolve it in")));
        };
        let path = base.join(relative);
        // A URI naming a device or directory would hang or fail obscurely inside the reader.
        match std::fs::metadata(&path) {
            Ok(m) if !m.is_file() => return Err(refuse(format!("\"{}\" is not a regular file", path.display()))),
            Ok(m) if m.len() > MAX_FILE_BYTES => {
                return Err(SceneError::TooLarge {
                    source_name: name.into(),
                    what: "external buffer size in bytes",
                    count: m.len(),
                    limit: MAX_FILE_BYTES,
                });
            }
            Ok(_) => {}
            Err(e) => return Err(refuse(format!("cannot open \"{}\": {e}", path.display()))),
        }
    }
    Ok(())
}

pub(crate) fn map_gltf_error(e: gltf::Error, name: &str) -> SceneError {
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
