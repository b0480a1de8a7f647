//! The flattened triangle mesh every other stage consumes, its bounding box and the load report.
//!
//! A scene, however it was authored, becomes one indexed triangle list in world space. The
//! triangle order is a public contract (see [`crate::gltf_load`]): hit files store triangle
//! indices, so two tools that load the same file must agree on which triangle is number `i`.

use glam::Vec3;
use serde::Serialize;

/// Axis-aligned bounding box. An empty box has `min > max` on every axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in points {
            b.grow(*p);
        }
        b
    }

    /// The bounds of every corner of `tris`.
    pub fn of_triangles(tris: &[[Vec3; 3]]) -> Aabb {
        Aabb::of_triangles_and_widest(tris).0
    }

    /// The bounds of every corner of `tris` and the widest triangle's extent (`max − min` of its
    /// corners) on each axis, in one loop on SIMD lanes (`Vec3A`; min and max are exact). The
    /// earlier nine scalar lanes per corner coordinate did not compile to SIMD and were 2–2.5×
    /// slower on scenes of 100k to 2M triangles (README, levers).
    pub fn of_triangles_and_widest(tris: &[[Vec3; 3]]) -> (Aabb, Vec3) {
        use glam::Vec3A;
        if tris.is_empty() {
            return (Aabb::EMPTY, Vec3::ZERO);
        }
        let (mut lo, mut hi, mut widest) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, Vec3A::ZERO);
        for t in tris {
            let (a, b, c) = (Vec3A::from(t[0]), Vec3A::from(t[1]), Vec3A::from(t[2]));
            let (tl, th) = (a.min(b).min(c), a.max(b).max(c));
            lo = lo.min(tl);
            hi = hi.max(th);
            widest = widest.max(th - tl);
        }
        (Aabb { min: lo.into(), max: hi.into() }, widest.into())
    }

    pub fn extent(&self) -> Vec3 {
        if self.is_empty() { Vec3::ZERO } else { self.max - self.min }
    }

    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// The length of the box's diagonal, at any scale ([`crate::scaled::length_scaled`]).
    pub fn diagonal(&self) -> f32 {
        crate::scaled::length_scaled(self.extent())
    }
}

/// One indexed triangle mesh in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The three corners of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// All triangles as corner triples, in triangle order: the form the grid and the
    /// intersection code work on (no index indirection on the hot path).
    pub fn triangles(&self) -> Vec<[Vec3; 3]> {
        let mut out = Vec::with_capacity(self.indices.len());
        self.triangles_into(&mut out);
        out
    }

    /// [`Mesh::triangles`] into a reused buffer (animation frames).
    pub fn triangles_into(&self, out: &mut Vec<[Vec3; 3]>) {
        out.clear();
        out.extend((0..self.indices.len()).map(|i| self.triangle(i)));
    }

    pub fn bounds(&self) -> Aabb {
        // Only referenced vertices count: an unused vertex far away must not stretch the grid.
        let mut b = Aabb::EMPTY;
        for tri in &self.indices {
            for &i in tri {
                b.grow(self.positions[i as usize]);
            }
        }
        b
    }

    /// Appends `other`, re-basing its indices; triangle order is `self` then `other`.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.indices.extend(other.indices.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
    }

    /// Number of zero-area triangles (exactly collinear or coincident corners, computed in f64
    /// so that only truly degenerate triangles count).
    pub fn degenerate_count(&self) -> usize {
        (0..self.indices.len()).filter(|&i| is_degenerate(self.triangle(i))).count()
    }
}

/// True when the triangle has zero area (its corners are collinear or coincide).
pub fn is_degenerate(t: [Vec3; 3]) -> bool {
    let a = t[0].as_dvec3();
    let e1 = t[1].as_dvec3() - a;
    let e2 = t[2].as_dvec3() - a;
    e1.cross(e2) == glam::DVec3::ZERO
}

/// What loading a scene found: printed by `gridrt info`, shown in the app.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LoadReport {
    pub source: String,
    pub triangles: usize,
    pub vertices: usize,
    pub bounds_min: [f32; 3],
    pub bounds_max: [f32; 3],
    pub degenerate_triangles: usize,
    pub meshes: usize,
    pub primitives: usize,
    /// Primitives that were not turned into triangles, with the reason (points, lines, …).
    pub skipped_primitives: Vec<String>,
    /// Clips, skins and morph targets, when the file has any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub animation: Option<crate::pose::AnimationSummary>,
    /// The animation time the triangles were posed at (`None`: the rest pose).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose: Option<crate::pose::PoseNote>,
}

impl LoadReport {
    pub fn for_mesh(source: &str, mesh: &Mesh) -> LoadReport {
        let b = mesh.bounds();
        let (min, max) = if b.is_empty() { (Vec3::ZERO, Vec3::ZERO) } else { (b.min, b.max) };
        LoadReport {
            source: source.to_string(),
            triangles: mesh.triangle_count(),
            vertices: mesh.positions.len(),
            bounds_min: min.to_array(),
            bounds_max: max.to_array(),
            degenerate_triangles: mesh.degenerate_count(),
            meshes: 1,
            primitives: 1,
            skipped_primitives: Vec::new(),
            animation: None,
            pose: None,
        }
    }

    /// Refreshes what depends on the positions (bounds, degenerate count) after posing.
    pub fn reposed(&mut self, mesh: &Mesh, pose: Option<crate::pose::PoseNote>) {
        let fresh = LoadReport::for_mesh(&self.source, mesh);
        self.bounds_min = fresh.bounds_min;
        self.bounds_max = fresh.bounds_max;
        self.degenerate_triangles = fresh.degenerate_triangles;
        self.pose = pose;
    }
}

/// A coordinate as `info` prints it: six decimals at everyday magnitudes, seven significant
/// digits in scientific notation for a scene nanometres or light years across (whose corners
/// would otherwise print as 0.000000 or as thirty digits).
struct Coordinate(f32);

impl std::fmt::Display for Coordinate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.0;
        if v == 0.0 || (1e-3..1e7).contains(&v.abs()) { write!(f, "{v:.6}") } else { write!(f, "{v:.6e}") }
    }
}

impl std::fmt::Display for LoadReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "scene:       {}", self.source)?;
        writeln!(f, "triangles:   {}", self.triangles)?;
        writeln!(f, "vertices:    {}", self.vertices)?;
        writeln!(f, "meshes:      {} ({} primitives)", self.meshes, self.primitives)?;
        let ([a, b, c], [d, e, g]) = (self.bounds_min.map(Coordinate), self.bounds_max.map(Coordinate));
        writeln!(f, "bounds:      [{a}, {b}, {c}] .. [{d}, {e}, {g}]")?;
        writeln!(f, "degenerate:  {} zero-area triangles", self.degenerate_triangles)?;
        write!(f, "skipped:     {} primitives", self.skipped_primitives.len())?;
        for s in &self.skipped_primitives {
            write!(f, "\n  - {s}")?;
        }
        if let Some(a) = &self.animation {
            write!(
                f,
                "\nanimations:  {} (skins {}, {} joints, {} morph targets; {} skinned and {} morphed mesh instances)",
                a.clips.len(),
                a.skins,
                a.joints,
                a.morph_targets,
                a.skinned_instances,
                a.morphed_instances
            )?;
            for c in &a.clips {
                let name = c.name.as_deref().map(|n| format!(" {n:?}")).unwrap_or_default();
                write!(
                    f,
                    "\n  {}{name}: {:.3} s ({:.3}..{:.3} s), {} channels",
                    c.index,
                    c.end - c.start,
                    c.start,
                    c.end,
                    c.channels
                )?;
            }
        }
        if let Some(p) = &self.pose {
            write!(f, "\nposed at:    {p}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::Coordinate;

    /// Everyday coordinates print with six decimals; tiny and huge ones keep their digits.
    #[test]
    fn coordinates_print_at_every_scale() {
        let s = |v: f32| Coordinate(v).to_string();
        assert_eq!((s(0.0), s(1.5), s(-0.0946)), ("0.000000".into(), "1.500000".into(), "-0.094600".into()));
        assert_eq!((s(1e-12), s(-3e20)), ("1.000000e-12".into(), "-3.000000e20".into()));
    }
}
