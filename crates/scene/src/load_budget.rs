//! The load budget: before any buffer is decoded, count what a glTF document would make the
//! loader allocate and refuse it when it is over the limits, with an error naming the node or
//! accessor at fault and the numbers.
//!
//! A 1 KB file can describe 2^28 instances of a mesh through a node graph that shares children,
//! or a sparse accessor of 10^9 elements with no data behind it. So the counts come from the
//! JSON alone: instanced triangles, vertices and node visits through the graph (shared children
//! counted once per path, duplicates included), every accessor the loader or a future posing
//! step reads (sparse ones included), morph targets × vertices, animation keys and skins.

use gltf::Document;

use crate::error::SceneError;

/// Largest number of triangles in one flattened scene (indices must fit in `u32` with room for
/// the "no hit" marker `0xFFFF_FFFF`).
pub const MAX_TRIANGLES: u64 = 1 << 28;

/// What one file may make the loader allocate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoadLimits {
    /// Most triangles after instancing (`--max-triangles`); never above [`MAX_TRIANGLES`].
    pub max_triangles: u64,
    /// Most bytes for buffers, decoded accessors and the flattened mesh (`--max-load-bytes`).
    pub max_bytes: u64,
}

impl LoadLimits {
    /// Default triangle limit: 2^26 (64 Mi) triangles.
    pub const DEFAULT_MAX_TRIANGLES: u64 = 1 << 26;
}

impl Default for LoadLimits {
    fn default() -> LoadLimits {
        LoadLimits { max_triangles: LoadLimits::DEFAULT_MAX_TRIANGLES, max_bytes: default_max_bytes() }
    }
}

/// Default byte budget: a quarter of physical memory and at most half of the process's
/// address-space limit (`ulimit -v`), at least 64 MiB; 1 GiB where neither can be read
/// (the browser, systems without `/proc`).
/// Read once per process (the limits of a running process do not change under it).
pub fn default_max_bytes() -> u64 {
    static BYTES: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    *BYTES.get_or_init(measure_max_bytes)
}

fn measure_max_bytes() -> u64 {
    let physical = read_proc_number("/proc/meminfo", "MemTotal:").map(|kb| kb.saturating_mul(1024) / 4);
    let address_space = read_proc_number("/proc/self/limits", "Max address space").map(|b| b / 2);
    let budget = match (physical, address_space) {
        (Some(p), Some(a)) => p.min(a),
        (Some(p), None) => p,
        (None, Some(a)) => a.min(1 << 30),
        (None, None) => 1 << 30,
    };
    budget.max(64 << 20)
}

/// The first number after `key` on the line that starts with it (`None` for "unlimited").
fn read_proc_number(path: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(path).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].split_whitespace().next()?.parse().ok()
}

/// What the document will allocate, as counted before loading.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Plan {
    pub triangles: u64,
    pub vertices: u64,
    pub bytes: u64,
    /// Per node: a mesh or a skin joint at it or below it (subtrees without one need no visit).
    pub visit_below: Vec<bool>,
    /// Per node, its `EXT_mesh_gpu_instancing` (parsed and checked once, here).
    pub instancing: Vec<Option<crate::instancing::NodeInstancing>>,
}

/// The flag that raises each limit, named in the errors.
const TRIANGLES_FLAG: &str = "--max-triangles";
const BYTES_FLAG: &str = "--max-load-bytes";

struct Counter<'a> {
    name: &'a str,
    limits: LoadLimits,
    bytes: u128,
}

impl Counter<'_> {
    /// Adds `count` elements of `elem` bytes for `item`, refusing one item over the budget alone.
    fn add(&mut self, item: impl FnOnce() -> String, count: u64, elem: u64) -> Result<(), SceneError> {
        let bytes = count as u128 * elem as u128;
        if bytes > self.limits.max_bytes as u128 {
            return Err(SceneError::OverBudget {
                source_name: self.name.into(),
                detail: format!(
                    "{}: {count} elements of {elem} bytes need {bytes} bytes, more than the load budget of {} bytes",
                    item(),
                    self.limits.max_bytes
                ),
                flag: BYTES_FLAG,
            });
        }
        self.bytes += bytes;
        Ok(())
    }
}

/// Counts what loading `doc` from the `roots` allocates and checks it against `limits`.
/// `roots` lists root node indices; a root listed twice is instanced twice.
pub(crate) fn check(
    doc: &Document,
    roots: &[usize],
    limits: &LoadLimits,
    file_bytes: u64,
    name: &str,
) -> Result<Plan, SceneError> {
    let max_triangles = limits.max_triangles.min(MAX_TRIANGLES);
    let mut c = Counter { name, limits: *limits, bytes: file_bytes as u128 };

    for buffer in doc.buffers() {
        c.add(|| format!("buffer {}", buffer.index()), buffer.length() as u64, 1)?;
    }

    // Per mesh: triangles and vertices one instance adds; decoding cost once per mesh.
    let mut mesh_tris = vec![0u64; doc.meshes().len()];
    let mut mesh_verts = vec![0u64; doc.meshes().len()];
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let at = || format!("mesh {}, primitive {}", mesh.index(), prim.index());
            let Some(pos) = prim.get(&gltf::Semantic::Positions) else { continue };
            let v = pos.count() as u64;
            // Read as f64 components, then kept as f32.
            c.add(|| format!("{}: POSITION accessor {}", at(), pos.index()), v, 36)?;
            let idx_count = match prim.indices() {
                Some(acc) => {
                    c.add(|| format!("{}: indices accessor {}", at(), acc.index()), acc.count() as u64, 4)?;
                    acc.count() as u64
                }
                None => v,
            };
            let t = match prim.mode() {
                gltf::mesh::Mode::Triangles => idx_count / 3,
                gltf::mesh::Mode::TriangleStrip | gltf::mesh::Mode::TriangleFan => idx_count.saturating_sub(2),
                _ => 0,
            };
            if t > 0 {
                c.add(|| format!("{}: {t} triangles", at()), t, 12)?;
                mesh_tris[mesh.index()] += t;
                mesh_verts[mesh.index()] += v;
            }
            for (k, target) in prim.morph_targets().enumerate() {
                if let Some(acc) = target.positions() {
                    c.add(
                        || format!("{}: morph target {k} POSITION accessor {}", at(), acc.index()),
                        acc.count() as u64,
                        decoded(&acc),
                    )?;
                }
            }
            for (sem, acc) in prim.attributes() {
                if matches!(sem, gltf::Semantic::Joints(_) | gltf::Semantic::Weights(_)) {
                    c.add(|| format!("{}: {sem:?} accessor {}", at(), acc.index()), acc.count() as u64, decoded(&acc))?;
                }
            }
        }
    }
    for skin in doc.skins() {
        if let Some(acc) = skin.inverse_bind_matrices() {
            c.add(
                || format!("skin {}: inverseBindMatrices accessor {}", skin.index(), acc.index()),
                acc.count() as u64,
                decoded(&acc),
            )?;
        }
    }
    for anim in doc.animations() {
        for s in anim.samplers() {
            let what =
                |k: &str, a: usize| format!("animation {} sampler {}: {k} accessor {a}", anim.index(), s.index());
            c.add(|| what("input", s.input().index()), s.input().count() as u64, decoded(&s.input()))?;
            c.add(|| what("output", s.output().index()), s.output().count() as u64, decoded(&s.output()))?;
        }
    }

    // Instances of each node through the graph: parents before children, counts saturating.
    let children: Vec<Vec<usize>> = doc.nodes().map(|n| n.children().map(|c| c.index()).collect()).collect();
    let order = topological_order(&children, roots, name)?;
    let mut inst = vec![0u128; children.len()];
    for &r in roots {
        inst[r] = inst[r].saturating_add(1);
    }
    for &n in &order {
        let here = inst[n];
        for &child in &children[n] {
            inst[child] = inst[child].saturating_add(here);
        }
    }
    // Node visits are cheap but must end: a graph of empty nodes can be as large as one of meshes.
    let max_visits = max_triangles.max(1 << 20);
    let visits: u128 = inst.iter().fold(0u128, |a, &b| a.saturating_add(b));
    if visits > max_visits as u128 {
        let (node, &times) = inst.iter().enumerate().max_by_key(|(_, t)| **t).expect("a visited node");
        return Err(SceneError::OverBudget {
            source_name: name.into(),
            detail: format!(
                "node {node} is reached {} times through the node graph ({} node instances in all), more than the limit of {max_visits}",
                show(times),
                show(visits)
            ),
            flag: TRIANGLES_FLAG,
        });
    }
    let node_mesh: Vec<usize> = doc.nodes().map(|n| n.mesh().map_or(usize::MAX, |m| m.index())).collect();
    let (mut triangles, mut vertices, mut worst) = (0u128, 0u128, (0usize, 0u128));
    let mut instancing = vec![None; node_mesh.len()];
    for node in doc.nodes() {
        let Some(mesh) = node.mesh() else { continue };
        // EXT_mesh_gpu_instancing: the mesh once per instance, wherever the node is reached.
        if let Some(gpu) = crate::instancing::NodeInstancing::of(doc, &node, name)? {
            if inst[node.index()] > 0 {
                let at = || format!("node {}: {} instances", node.index(), gpu.count);
                c.add(at, gpu.count as u64, gpu.bytes_per_instance())?;
            }
            inst[node.index()] = inst[node.index()].saturating_mul(gpu.count as u128);
            instancing[node.index()] = Some(gpu);
        }
        let t = inst[node.index()].saturating_mul(mesh_tris[mesh.index()] as u128);
        triangles = triangles.saturating_add(t);
        vertices = vertices.saturating_add(inst[node.index()].saturating_mul(mesh_verts[mesh.index()] as u128));
        if t > worst.1 {
            worst = (node.index(), t);
        }
    }
    if triangles > max_triangles as u128 {
        let (node, t) = worst;
        return Err(SceneError::OverBudget {
            source_name: name.into(),
            detail: format!(
                "{} triangles after instancing (node {node}: {} instances of mesh {} give {}), more than the limit of {max_triangles}",
                show(triangles),
                show(inst[node]),
                node_mesh[node],
                show(t)
            ),
            flag: TRIANGLES_FLAG,
        });
    }
    if vertices > u32::MAX as u128 {
        return Err(SceneError::OverBudget {
            source_name: name.into(),
            detail: format!("{} vertices after instancing, more than the 32-bit index limit", show(vertices)),
            flag: TRIANGLES_FLAG,
        });
    }
    c.add(|| "the flattened mesh".into(), triangles as u64, 12)?;
    c.add(|| "the flattened mesh's vertices".into(), vertices as u64, 12)?;
    if c.bytes > limits.max_bytes as u128 {
        return Err(SceneError::OverBudget {
            source_name: name.into(),
            detail: format!(
                "loading needs about {} bytes ({} triangles, {} vertices after instancing), more than the load budget of {} bytes",
                c.bytes, triangles, vertices, limits.max_bytes
            ),
            flag: BYTES_FLAG,
        });
    }
    // Children come after their parents in `order`: walk it backwards.
    let mut visit_below: Vec<bool> = node_mesh.iter().map(|&m| m != usize::MAX).collect();
    for j in doc.skins().flat_map(|s| s.joints()) {
        visit_below[j.index()] = true;
    }
    for &n in order.iter().rev() {
        visit_below[n] = visit_below[n] || children[n].iter().any(|&c| visit_below[c]);
    }
    Ok(Plan { triangles: triangles as u64, vertices: vertices as u64, bytes: c.bytes as u64, visit_below, instancing })
}

/// Bytes per element once decoded ([`crate::accessor::read_components`] yields f64 components).
fn decoded(acc: &gltf::Accessor) -> u64 {
    acc.dimensions().multiplicity() as u64 * 8
}

/// A count that may have saturated.
fn show(n: u128) -> String {
    if n == u128::MAX { "more than 2^128".into() } else { n.to_string() }
}

/// The nodes reachable from `roots`, parents before children, each once; an error for a cycle.
/// Iterative, so a deep hierarchy cannot exhaust the stack.
fn topological_order(children: &[Vec<usize>], roots: &[usize], name: &str) -> Result<Vec<usize>, SceneError> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        Open,
        Done,
    }
    let mut mark = vec![Mark::New; children.len()];
    let mut post = Vec::with_capacity(children.len());
    let mut stack: Vec<(usize, usize)> = Vec::new();
    for &r in roots {
        if mark[r] != Mark::New {
            continue;
        }
        mark[r] = Mark::Open;
        stack.push((r, 0));
        while let Some(top) = stack.last_mut() {
            let (n, k) = *top;
            if let Some(&child) = children[n].get(k) {
                top.1 += 1;
                match mark[child] {
                    Mark::New => {
                        mark[child] = Mark::Open;
                        stack.push((child, 0));
                    }
                    Mark::Open => {
                        let start = stack.iter().position(|&(s, _)| s == child).unwrap_or(0);
                        let cycle: Vec<usize> = stack[start..].iter().map(|&(s, _)| s).collect();
                        return Err(SceneError::InvalidNode {
                            source_name: name.into(),
                            node: child,
                            detail: format!("is its own ancestor (cycle through nodes {cycle:?})"),
                        });
                    }
                    Mark::Done => {}
                }
            } else {
                mark[n] = Mark::Done;
                post.push(n);
                stack.pop();
            }
        }
    }
    post.reverse();
    Ok(post)
}
