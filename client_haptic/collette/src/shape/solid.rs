//! A closed mesh that answers "is this point inside?" exactly: the reference of the Monte Carlo
//! benchmarks (collette's `volume_accuracy`, haptic_rig's `fidelity`), not a runtime query.
//!
//! You need this module to compute an exact answer another way than collette does: parry3d's
//! pseudo-normal point containment, behind a voxel grid that answers the points far from the surface.

use glam::Vec3;
use parry3d::query::PointQuery;
use rayon::prelude::*;

use crate::packing::to_parry_oriented;
use crate::shape::TriMesh;

/// A mesh's inside, exactly (slow to build: one parry projection per voxel, in parallel).
pub struct Solid {
    parry: parry3d::shape::TriMesh,
    volume: f64,
    origin: Vec3,
    h: f32,
    dims: [usize; 3],
    /// Per voxel: 1 surely inside, -1 surely outside, 0 ask parry.
    sure: Vec<i8>,
}

impl Solid {
    /// The inside of `mesh`, with `voxels` voxels along its box's longest side answering the points
    /// that are not near the surface (96 is quick to build; 256 answers most points of a thin region
    /// near the surface without parry).
    pub fn new(mesh: &TriMesh, voxels: usize) -> Self {
        let parry = to_parry_oriented(mesh);
        let aabb = mesh.aabb();
        let h = aabb.extents().max_element() / voxels.max(1) as f32;
        let origin = aabb.min - Vec3::splat(h);
        let dims = [0, 1, 2].map(|a| ((aabb.extents()[a] + 2.0 * h) / h).ceil() as usize);
        let half_diagonal = h * 3f32.sqrt() * 0.5;
        let sure = (0..dims[0] * dims[1] * dims[2])
            .into_par_iter()
            .map(|i| {
                let (x, y, z) = (i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1]));
                let c = origin + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * h;
                let q = parry3d::math::Vector::new(c.x, c.y, c.z);
                let proj = parry.project_local_point(q, false);
                let far = (proj.point - q).length() > half_diagonal * 1.01;
                match (far, proj.is_inside) {
                    (true, true) => 1,
                    (true, false) => -1,
                    _ => 0,
                }
            })
            .collect();
        Self { parry, volume: mesh.volume() as f64, origin, h, dims, sure }
    }

    /// The mesh's volume.
    pub fn volume(&self) -> f64 {
        self.volume
    }

    /// Whether `p` (the mesh's frame) is inside.
    pub fn contains(&self, p: Vec3) -> bool {
        let g = (p - self.origin) / self.h;
        if g.min_element() < 0.0 {
            return false;
        }
        let (x, y, z) = (g.x as usize, g.y as usize, g.z as usize);
        if x >= self.dims[0] || y >= self.dims[1] || z >= self.dims[2] {
            return false;
        }
        match self.sure[x + self.dims[0] * (y + self.dims[1] * z)] {
            1 => true,
            -1 => false,
            _ => self.parry.contains_local_point(parry3d::math::Vector::new(p.x, p.y, p.z)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_contains_its_inside_and_not_its_outside() {
        let (v, t) = crate::shape::box_buffers(Vec3::new(0.02, 0.01, 0.03));
        let solid = Solid::new(&TriMesh::new(v, t).expect("box"), 16);
        for p in [Vec3::ZERO, Vec3::new(0.0199, 0.0, 0.0), Vec3::new(0.0, -0.0099, 0.0299)] {
            assert!(solid.contains(p), "{p} is inside");
        }
        for p in [Vec3::new(0.0201, 0.0, 0.0), Vec3::new(0.0, 0.0101, 0.0), Vec3::splat(1.0)] {
            assert!(!solid.contains(p), "{p} is outside");
        }
        assert!((solid.volume() - 0.04 * 0.02 * 0.06).abs() < 1e-9);
    }
}
