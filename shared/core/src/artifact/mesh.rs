//! The haptic triangle mesh sent to the Phantom client, and the checks that make it safe to feed to
//! collision detection (closed, manifold, outward-facing, finite).

use std::collections::HashMap;

use glam::Vec3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Smallest triangle area accepted by [`HapticMesh::validate`], m² (0.01 mm²).
pub const MIN_TRIANGLE_AREA_M2: f32 = 1e-8;

/// A triangle mesh in metres; closed and wound counter-clockwise seen from outside.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct HapticMesh {
    /// Vertex positions, metres, +y up, centred near the origin.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as indices into `vertices`, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

/// Why a mesh is not a valid closed haptic surface; names the first offender found.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum MeshError {
    /// The mesh has no triangles.
    #[error("mesh has no triangles")]
    Empty,
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} is not finite")]
    NonFiniteVertex {
        /// Index of the vertex.
        vertex: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but there are only {vertex_count} vertices")]
    IndexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices in the mesh.
        vertex_count: usize,
    },
    /// A triangle repeats a vertex or has (almost) no area.
    #[error("triangle {triangle} is degenerate (area {area_m2} m²)")]
    DegenerateTriangle {
        /// Index of the triangle.
        triangle: usize,
        /// Its area, m².
        area_m2: f32,
    },
    /// A directed edge is used twice: more than two triangles meet there, or neighbours disagree on winding.
    #[error("edge {edge:?} is used twice in the same direction (second time by triangle {triangle})")]
    NonManifoldEdge {
        /// The edge as (from, to) vertex indices.
        edge: [u32; 2],
        /// The triangle that used it a second time.
        triangle: usize,
    },
    /// An edge has no neighbouring triangle on its other side: the mesh has a hole.
    #[error("edge {edge:?} of triangle {triangle} is open (no triangle on the other side)")]
    OpenEdge {
        /// The edge as (from, to) vertex indices.
        edge: [u32; 2],
        /// The triangle that owns it.
        triangle: usize,
    },
    /// The enclosed volume is not positive: the mesh is wound inside out.
    #[error("signed volume is {volume_m3} m³; the mesh is inside out")]
    InsideOut {
        /// The signed volume, m³.
        volume_m3: f32,
    },
}

impl HapticMesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corners of triangle `t`, metres (panics if out of range).
    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|i| Vec3::from_array(self.vertices[i as usize]))
    }

    /// Corners of every triangle, metres, skipping triangles with an index out of range.
    pub fn triangle_corners(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        self.triangles.iter().filter_map(|t| {
            let p = |i: u32| self.vertices.get(i as usize).map(|p| Vec3::from_array(*p));
            Some([p(t[0])?, p(t[1])?, p(t[2])?])
        })
    }

    /// Enclosed volume, m³; positive when the triangles face outwards.
    pub fn signed_volume(&self) -> f32 {
        // Summed in f64: thousands of small tetrahedra would lose digits in f32.
        let mut v = 0.0f64;
        for t in &self.triangles {
            if let Some([a, b, c]) = corners_checked(&self.vertices, t) {
                v += a.dot(b.cross(c));
            }
        }
        (v / 6.0) as f32
    }

    /// Centre of mass of the enclosed solid (uniform density), metres.
    ///
    /// Falls back to the centre of the bounds when the mesh encloses no volume.
    pub fn centroid(&self) -> Vec3 {
        let mut weighted = glam::DVec3::ZERO;
        let mut volume = 0.0f64;
        for t in &self.triangles {
            let Some([a, b, c]) = corners_checked(&self.vertices, t) else { continue };
            let v = a.dot(b.cross(c));
            weighted += (a + b + c) * v / 4.0;
            volume += v;
        }
        if volume.abs() > 1e-15 && weighted.is_finite() {
            (weighted / volume).as_vec3()
        } else {
            let (lo, hi) = self.bounds();
            (lo + hi) * 0.5
        }
    }

    /// The same mesh moved by `offset`, metres (e.g. into the workbench frame).
    pub fn translated(&self, offset: Vec3) -> HapticMesh {
        let vertices = self.vertices.iter().map(|p| (Vec3::from_array(*p) + offset).to_array()).collect();
        HapticMesh { vertices, triangles: self.triangles.clone() }
    }

    /// Axis-aligned bounds (min, max), metres; zeros for an empty mesh.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut it = self.vertices.iter().map(|p| Vec3::from_array(*p));
        let Some(first) = it.next() else { return (Vec3::ZERO, Vec3::ZERO) };
        it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)))
    }

    /// Checks that the mesh is a valid haptic surface, naming the first offender.
    ///
    /// Valid means: finite vertices, indices in range, no triangle below [`MIN_TRIANGLE_AREA_M2`],
    /// closed, manifold, consistently wound, and a positive enclosed volume (outward).
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if let Some(vertex) = self.vertices.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(MeshError::NonFiniteVertex { vertex });
        }
        let vertex_count = self.vertices.len();
        for (triangle, tri) in self.triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= vertex_count) {
                return Err(MeshError::IndexOutOfRange { triangle, index, vertex_count });
            }
            let [a, b, c] = self.corners(triangle);
            let area_m2 = 0.5 * (b - a).cross(c - a).length();
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || area_m2 < MIN_TRIANGLE_AREA_M2 {
                return Err(MeshError::DegenerateTriangle { triangle, area_m2 });
            }
        }
        // Closed + manifold + consistently wound <=> every directed edge occurs once and its
        // reverse occurs once.
        let mut directed: HashMap<[u32; 2], usize> = HashMap::with_capacity(self.triangles.len() * 3);
        for (triangle, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let edge = [tri[k], tri[(k + 1) % 3]];
                if directed.insert(edge, triangle).is_some() {
                    return Err(MeshError::NonManifoldEdge { edge, triangle });
                }
            }
        }
        for (triangle, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let edge = [tri[k], tri[(k + 1) % 3]];
                if !directed.contains_key(&[edge[1], edge[0]]) {
                    return Err(MeshError::OpenEdge { edge, triangle });
                }
            }
        }
        let volume_m3 = self.signed_volume();
        if volume_m3.is_nan() || volume_m3 <= 0.0 {
            return Err(MeshError::InsideOut { volume_m3 });
        }
        Ok(())
    }
}

/// The corners of `t` in f64, or `None` if an index is out of range.
fn corners_checked(vertices: &[[f32; 3]], t: &[u32; 3]) -> Option<[glam::DVec3; 3]> {
    let p = |i: u32| vertices.get(i as usize).map(|p| Vec3::from_array(*p).as_dvec3());
    Some([p(t[0])?, p(t[1])?, p(t[2])?])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> HapticMesh {
        HapticMesh {
            vertices: vec![[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn an_outward_tetrahedron_is_valid_with_its_volume() {
        let m = tetrahedron();
        assert_eq!(m.validate(), Ok(()));
        assert!((m.signed_volume() - 0.001 / 6.0).abs() < 1e-9);
        assert_eq!(m.triangle_count(), 4);
    }

    #[test]
    fn the_centroid_follows_a_translation() {
        let m = tetrahedron();
        assert!((m.centroid() - Vec3::splat(0.025)).length() < 1e-6);
        let moved = m.translated(Vec3::new(1.0, 2.0, -3.0));
        assert!((moved.centroid() - Vec3::new(1.025, 2.025, -2.975)).length() < 1e-5);
        assert_eq!(moved.validate(), Ok(()));
    }

    #[test]
    fn a_flipped_mesh_is_reported_inside_out() {
        let mut m = tetrahedron();
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
        assert!(matches!(m.validate(), Err(MeshError::InsideOut { .. })));
    }

    #[test]
    fn a_missing_triangle_is_reported_as_an_open_edge() {
        let mut m = tetrahedron();
        m.triangles.pop();
        assert!(matches!(m.validate(), Err(MeshError::OpenEdge { .. })));
    }

    #[test]
    fn one_flipped_triangle_is_reported_as_a_non_manifold_edge() {
        let mut m = tetrahedron();
        m.triangles[3].swap(1, 2);
        assert!(matches!(m.validate(), Err(MeshError::NonManifoldEdge { triangle: 3, .. })));
    }

    #[test]
    fn nan_vertices_bad_indices_and_slivers_are_named() {
        let mut m = tetrahedron();
        m.vertices[2][1] = f32::NAN;
        assert_eq!(m.validate(), Err(MeshError::NonFiniteVertex { vertex: 2 }));
        let mut m = tetrahedron();
        m.triangles[1][2] = 9;
        assert!(matches!(m.validate(), Err(MeshError::IndexOutOfRange { triangle: 1, index: 9, .. })));
        let mut m = tetrahedron();
        m.vertices[3] = [0.05, 0.05, 0.0];
        assert!(matches!(m.validate(), Err(MeshError::DegenerateTriangle { .. })));
    }
}
