//! Closed, consistently oriented triangle meshes: loading (OBJ or buffers), validation, exact volume.

use crate::bounding_volume::Aabb;
use crate::error::MeshError;
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;

/// A validated closed triangle mesh with outward-facing triangles (counter-clockwise seen from outside).
#[derive(Clone, Debug, PartialEq)]
pub struct TriMesh {
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Validates vertex and triangle buffers; an inward-oriented mesh is flipped to face outward.
    ///
    /// Errors name the first offending vertex, triangle or edge (in triangle order).
    pub fn new(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        validate(&vertices, &triangles)?;
        let mut mesh = Self { vertices, triangles };
        let volume = mesh.signed_volume();
        if volume == 0.0 || !volume.is_finite() {
            return Err(MeshError::ZeroVolume);
        }
        if volume < 0.0 {
            for t in &mut mesh.triangles {
                t.swap(1, 2);
            }
        }
        Ok(mesh)
    }

    /// Builds from flat buffers: `positions` as x,y,z triples and `indices` as triangle triples.
    pub fn from_buffers(positions: &[f32], indices: &[u32]) -> Result<Self, MeshError> {
        if !indices.len().is_multiple_of(3) {
            return Err(MeshError::RaggedIndices(indices.len()));
        }
        let vertices = positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let triangles = indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        Self::new(vertices, triangles)
    }

    /// Loads every object of an OBJ file (triangulated, merged into one mesh) and validates it.
    pub fn from_obj(path: impl AsRef<Path>) -> Result<Self, MeshError> {
        let path = path.as_ref();
        let options = tobj::LoadOptions { single_index: true, triangulate: true, ..Default::default() };
        let (models, _) = tobj::load_obj(path, &options)
            .map_err(|e| MeshError::Obj { path: path.to_owned(), message: e.to_string() })?;
        Self::merged(&models)
    }

    /// Reads an OBJ file's contents, as [`TriMesh::from_obj`] (materials are not read); `path` names the
    /// file in errors.
    pub fn from_obj_bytes(bytes: &[u8], path: &Path) -> Result<Self, MeshError> {
        let options = tobj::LoadOptions { single_index: true, triangulate: true, ..Default::default() };
        let (models, _) =
            tobj::load_obj_buf(&mut std::io::BufReader::new(bytes), &options, |_| Err(tobj::LoadError::OpenFileFailed))
                .map_err(|e| MeshError::Obj { path: path.to_owned(), message: e.to_string() })?;
        Self::merged(&models)
    }

    /// Every model's triangles in one mesh, validated.
    fn merged(models: &[tobj::Model]) -> Result<Self, MeshError> {
        let (mut positions, mut indices) = (Vec::new(), Vec::new());
        for model in models {
            let base = (positions.len() / 3) as u32;
            positions.extend_from_slice(&model.mesh.positions);
            indices.extend(model.mesh.indices.iter().map(|i| i + base));
        }
        Self::from_buffers(&positions, &indices)
    }

    /// The vertices.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// The triangles (vertex index triples, outward-facing).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The same mesh with every vertex mapped by `f` (e.g. scaling to metres); re-validated.
    pub fn map_vertices(&self, f: impl Fn(Vec3) -> Vec3) -> Result<Self, MeshError> {
        Self::new(self.vertices.iter().map(|&v| f(v)).collect(), self.triangles.clone())
    }

    /// Exact enclosed volume (divergence theorem over the triangles), always positive.
    pub fn volume(&self) -> f32 {
        self.signed_volume().abs()
    }

    fn signed_volume(&self) -> f32 {
        // Accumulate in f64 around the centroid of the box for accuracy.
        let c = self.aabb().center().as_dvec3();
        let mut sum = 0.0f64;
        for t in &self.triangles {
            let [a, b, d] = t.map(|i| self.vertices[i as usize].as_dvec3() - c);
            sum += a.dot(b.cross(d));
        }
        (sum / 6.0) as f32
    }

    /// Axis-aligned bounding box of the vertices.
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(&self.vertices)
    }
}

fn validate(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Result<(), MeshError> {
    if triangles.is_empty() {
        return Err(MeshError::Empty);
    }
    if let Some(i) = vertices.iter().position(|v| !v.is_finite()) {
        return Err(MeshError::NonFiniteVertex { vertex: i as u32 });
    }
    let diag = Aabb::from_points(vertices).extents().length();
    let area_eps = (diag * diag * 1e-12).max(f32::MIN_POSITIVE);
    for (ti, t) in triangles.iter().enumerate() {
        if let Some(&v) = t.iter().find(|&&v| v as usize >= vertices.len()) {
            return Err(MeshError::IndexOutOfRange { triangle: ti, vertex: v, vertex_count: vertices.len() });
        }
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let degenerate = t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || (b - a).cross(c - a).length() <= area_eps;
        if degenerate {
            return Err(MeshError::DegenerateTriangle { triangle: ti, a: t[0], b: t[1], c: t[2] });
        }
    }
    // Each directed edge must appear exactly once and its reverse exactly once.
    let mut directed: HashMap<(u32, u32), usize> = HashMap::with_capacity(triangles.len() * 3);
    for (ti, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let e = (t[k], t[(k + 1) % 3]);
            if let Some(&first) = directed.get(&e) {
                return Err(MeshError::InconsistentOrientation { a: e.0, b: e.1, first, second: ti });
            }
            directed.insert(e, ti);
        }
    }
    for (ti, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if !directed.contains_key(&(b, a)) {
                return Err(MeshError::OpenEdge { a, b, triangle: ti, count: 1 });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::box_buffers;

    fn unit_box() -> TriMesh {
        let (v, t) = box_buffers(Vec3::splat(0.5));
        TriMesh::new(v, t).expect("box is valid")
    }

    #[test]
    fn a_box_has_its_exact_volume() {
        let (v, t) = box_buffers(Vec3::new(1.0, 2.0, 3.0));
        let m = TriMesh::new(v, t).expect("valid");
        assert!((m.volume() - 48.0).abs() < 1e-4);
    }

    #[test]
    fn an_inward_mesh_is_flipped_outward() {
        let (v, mut t) = box_buffers(Vec3::splat(0.5));
        for tri in &mut t {
            tri.swap(0, 1);
        }
        let m = TriMesh::new(v, t).expect("valid");
        assert!(m.signed_volume() > 0.0);
        assert!((m.volume() - unit_box().volume()).abs() < 1e-6);
    }

    #[test]
    fn a_missing_triangle_names_the_open_edge() {
        let (v, mut t) = box_buffers(Vec3::splat(0.5));
        t.remove(3);
        let e = TriMesh::new(v, t).expect_err("open");
        assert!(matches!(e, MeshError::OpenEdge { .. }), "{e}");
        assert!(e.to_string().contains("edge"));
    }

    #[test]
    fn a_flipped_triangle_is_an_orientation_error() {
        let (v, mut t) = box_buffers(Vec3::splat(0.5));
        t[5].swap(0, 1);
        assert!(matches!(TriMesh::new(v, t), Err(MeshError::InconsistentOrientation { .. })));
    }

    #[test]
    fn nan_degenerate_and_out_of_range_inputs_are_refused() {
        let (mut v, t) = box_buffers(Vec3::splat(0.5));
        v[3].y = f32::NAN;
        assert_eq!(TriMesh::new(v, t.clone()), Err(MeshError::NonFiniteVertex { vertex: 3 }));
        let (v, mut t2) = box_buffers(Vec3::splat(0.5));
        t2[2] = [4, 4, 6];
        assert!(matches!(TriMesh::new(v.clone(), t2), Err(MeshError::DegenerateTriangle { triangle: 2, .. })));
        let mut t3 = t;
        t3[7][1] = 99;
        assert!(matches!(TriMesh::new(v, t3), Err(MeshError::IndexOutOfRange { triangle: 7, vertex: 99, .. })));
        assert_eq!(TriMesh::from_buffers(&[0.0; 9], &[0, 1]), Err(MeshError::RaggedIndices(2)));
        assert_eq!(TriMesh::new(vec![], vec![]), Err(MeshError::Empty));
    }

    #[test]
    fn a_missing_obj_file_is_an_error() {
        assert!(matches!(TriMesh::from_obj("/nonexistent/x.obj"), Err(MeshError::Obj { .. })));
    }
}
