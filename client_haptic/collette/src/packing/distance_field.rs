//! The voxel distance field: which voxel centres lie inside the mesh and how far they are from its surface.

use crate::shape::TriMesh;
use glam::Vec3;
use rayon::prelude::*;

/// Distances from the interior voxel centres of a regular grid to the mesh surface.
#[derive(Clone, Debug)]
pub struct DistanceField {
    /// Centre of voxel (0, 0, 0).
    pub origin: Vec3,
    /// Edge length of a voxel.
    pub voxel_size: f32,
    /// Number of voxels along x, y, z.
    pub dims: [usize; 3],
    /// Per voxel (x fastest): distance to the surface for interior voxels, a negative value outside.
    pub distance: Vec<f32>,
}

impl DistanceField {
    /// Samples `mesh` on a grid with `resolution` voxels along the longest side of its box.
    ///
    /// Inside/outside comes from the winding number along x-rows (exact for closed meshes); distances
    /// are exact point-triangle distances (parry's triangle-mesh projection). Rows run on all cores.
    pub fn new(mesh: &TriMesh, resolution: usize) -> Self {
        let bounds = mesh.aabb();
        let ext = bounds.extents();
        let h = ext.max_element() / resolution.max(2) as f32;
        let dims = [0, 1, 2].map(|a| ((ext[a] / h).ceil() as usize).max(1));
        let origin = bounds.center() - Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) * h * 0.5 + h * 0.5;
        let (nx, ny, nz) = (dims[0], dims[1], dims[2]);

        // Bin triangles by the rows (y, z) their projection may cover, in compressed-row form.
        let verts = mesh.vertices();
        let row_of = |y: f32, z: f32| -> (f32, f32) { ((y - origin.y) / h, (z - origin.z) / h) };
        let mut counts = vec![0u32; ny * nz + 1];
        let ranges: Vec<(usize, usize, usize, usize)> = mesh
            .triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| verts[i as usize]);
                let (y0, z0) = row_of(a.y.min(b.y).min(c.y), a.z.min(b.z).min(c.z));
                let (y1, z1) = row_of(a.y.max(b.y).max(c.y), a.z.max(b.z).max(c.z));
                let clampi = |v: f32, n: usize| (v.max(0.0) as usize).min(n);
                (
                    clampi(y0.ceil() - 1.0, ny),
                    clampi(y1.floor() + 2.0, ny),
                    clampi(z0.ceil() - 1.0, nz),
                    clampi(z1.floor() + 2.0, nz),
                )
            })
            .collect();
        for &(j0, j1, k0, k1) in &ranges {
            for k in k0..k1 {
                for j in j0..j1 {
                    counts[k * ny + j + 1] += 1;
                }
            }
        }
        for i in 1..counts.len() {
            counts[i] += counts[i - 1];
        }
        let mut fill = counts.clone();
        let mut bins = vec![0u32; counts[ny * nz] as usize];
        for (ti, &(j0, j1, k0, k1)) in ranges.iter().enumerate() {
            for k in k0..k1 {
                for j in j0..j1 {
                    let slot = &mut fill[k * ny + j];
                    bins[*slot as usize] = ti as u32;
                    *slot += 1;
                }
            }
        }

        let parry_mesh = to_parry(mesh);
        let tris = mesh.triangles();
        let mut distance = vec![-1.0f32; nx * ny * nz];
        distance.par_chunks_mut(nx).enumerate().for_each_init(
            Vec::new,
            |crossings: &mut Vec<(f32, i32)>, (row, out)| {
                let (j, k) = (row % ny, row / ny);
                // A tiny irrational offset keeps rows off shared edges and vertices.
                let y = origin.y + j as f32 * h + h * 1.3e-4;
                let z = origin.z + k as f32 * h + h * 0.7e-4;
                crossings.clear();
                for &ti in &bins[counts[row] as usize..counts[row + 1] as usize] {
                    let [a, b, c] = tris[ti as usize].map(|i| verts[i as usize]);
                    if let Some(hit) = row_crossing(a, b, c, y, z) {
                        crossings.push(hit);
                    }
                }
                if crossings.is_empty() {
                    return;
                }
                crossings.sort_by(|p, q| p.0.total_cmp(&q.0));
                let (mut next, mut winding) = (0usize, 0i32);
                for (i, d) in out.iter_mut().enumerate() {
                    let x = origin.x + i as f32 * h;
                    while next < crossings.len() && crossings[next].0 < x {
                        winding += crossings[next].1;
                        next += 1;
                    }
                    if winding != 0 {
                        let p = Vec3::new(x, origin.y + j as f32 * h, origin.z + k as f32 * h);
                        *d = surface_distance(&parry_mesh, p);
                    }
                }
            },
        );
        Self { origin, voxel_size: h, dims, distance }
    }

    /// Centre of voxel `index` (x fastest).
    #[inline]
    pub fn voxel_center(&self, index: usize) -> Vec3 {
        let (nx, ny) = (self.dims[0], self.dims[1]);
        let (i, j, k) = (index % nx, (index / nx) % ny, index / (nx * ny));
        self.origin + Vec3::new(i as f32, j as f32, k as f32) * self.voxel_size
    }

    /// Number of interior voxels.
    pub fn interior_count(&self) -> usize {
        self.distance.iter().filter(|d| **d > 0.0).count()
    }
}

/// Where the line `(t, y, z)` crosses triangle abc: x and the sign of the triangle's facing along x.
#[inline]
fn row_crossing(a: Vec3, b: Vec3, c: Vec3, y: f32, z: f32) -> Option<(f32, i32)> {
    // Barycentric coordinates in the yz projection, in f64 for robustness.
    let (ay, az, by, bz, cy, cz) = (a.y as f64, a.z as f64, b.y as f64, b.z as f64, c.y as f64, c.z as f64);
    let (y, z) = (y as f64, z as f64);
    let w0 = (by - y) * (cz - z) - (bz - z) * (cy - y);
    let w1 = (cy - y) * (az - z) - (cz - z) * (ay - y);
    let w2 = (ay - y) * (bz - z) - (az - z) * (by - y);
    let positive = w0 > 0.0 && w1 > 0.0 && w2 > 0.0;
    let negative = w0 < 0.0 && w1 < 0.0 && w2 < 0.0;
    if !positive && !negative {
        return None;
    }
    let sum = w0 + w1 + w2;
    let x = (w0 * a.x as f64 + w1 * b.x as f64 + w2 * c.x as f64) / sum;
    Some((x as f32, if positive { 1 } else { -1 }))
}

/// The mesh as a parry triangle mesh (for exact point distances and the parry comparison benchmark).
pub fn to_parry(mesh: &TriMesh) -> parry3d::shape::TriMesh {
    parry_with(mesh, parry3d::shape::TriMeshFlags::empty())
}

/// The mesh as a parry triangle mesh with pseudo-normals (`TriMeshFlags::ORIENTED`), so that parry's
/// point containment and projection tell inside from outside exactly.
pub fn to_parry_oriented(mesh: &TriMesh) -> parry3d::shape::TriMesh {
    parry_with(mesh, parry3d::shape::TriMeshFlags::ORIENTED)
}

/// The mesh as a parry triangle mesh built with `flags` (parry's `TriMesh::new` is `flags` empty).
fn parry_with(mesh: &TriMesh, flags: parry3d::shape::TriMeshFlags) -> parry3d::shape::TriMesh {
    let v = mesh.vertices().iter().map(|p| parry3d::math::Vector::new(p.x, p.y, p.z)).collect();
    parry3d::shape::TriMesh::with_flags(v, mesh.triangles().to_vec(), flags)
        .unwrap_or_else(|_| unreachable!("validated mesh is non-empty"))
}

#[inline]
fn surface_distance(mesh: &parry3d::shape::TriMesh, p: Vec3) -> f32 {
    use parry3d::query::PointQuery;
    let q = parry3d::math::Vector::new(p.x, p.y, p.z);
    (mesh.project_local_point(q, false).point - q).length()
}
