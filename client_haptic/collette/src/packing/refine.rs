//! Sub-voxel refinement of sphere centres: a pattern search on the exact free radius.
//!
//! Greedy packing on voxel centres loses most for the small spheres (radius near a voxel): moving a
//! centre by a fraction of a voxel can grow the sphere a lot. The free radius of a point is evaluated
//! exactly: distance to the surface (parry, with an oriented inside test) and to every placed sphere
//! (through a uniform hash grid).

use crate::shape::{Sphere, TriMesh};
use glam::{IVec3, Vec3};
use parry3d::query::PointQuery;
use std::collections::HashMap;

/// Placed spheres bucketed in a uniform grid (each sphere in every cell its box touches).
pub(crate) struct Refiner {
    mesh: parry3d::shape::TriMesh,
    cell: f32,
    cells: HashMap<IVec3, Vec<u32>>,
    spheres: Vec<Sphere>,
    step: f32,
    offset: f32,
}

impl Refiner {
    /// A refiner for `mesh` whose first search step is `step` (half a voxel).
    pub(crate) fn new(mesh: &TriMesh, step: f32, offset: f32) -> Self {
        let mesh = super::to_parry_oriented(mesh);
        Self { mesh, cell: step * 8.0, cells: HashMap::new(), spheres: Vec::new(), step, offset }
    }

    fn key(&self, p: Vec3) -> IVec3 {
        (p / self.cell).floor().as_ivec3()
    }

    /// Records a placed sphere.
    pub(crate) fn insert(&mut self, s: Sphere) {
        let index = self.spheres.len() as u32;
        self.spheres.push(s);
        let (lo, hi) = (self.key(s.center - s.radius), self.key(s.center + s.radius));
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    self.cells.entry(IVec3::new(x, y, z)).or_default().push(index);
                }
            }
        }
    }

    /// Exact free radius at `p` (negative outside the mesh or inside a sphere); only spheres within
    /// `reach` of `p` are considered, so the result is exact when it is below `reach`.
    fn free_radius(&self, p: Vec3, reach: f32) -> f32 {
        let q = parry3d::math::Vector::new(p.x, p.y, p.z);
        let proj = self.mesh.project_local_point(q, false);
        if !proj.is_inside {
            return -1.0;
        }
        let mut f = (proj.point - q).length() + self.offset;
        let (lo, hi) = (self.key(p - reach), self.key(p + reach));
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    if let Some(list) = self.cells.get(&IVec3::new(x, y, z)) {
                        for &i in list {
                            let s = &self.spheres[i as usize];
                            f = f.min(p.distance(s.center) - s.radius);
                        }
                    }
                }
            }
        }
        f
    }

    /// Moves `center` (free radius `radius`) within its voxel to a point with a larger free radius.
    pub(crate) fn refine(&self, center: Vec3, radius: f32) -> Sphere {
        let reach = radius + 2.0 * self.step;
        let (mut best, mut r) = (center, radius);
        let mut step = self.step;
        let dirs = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
        for _ in 0..12 {
            let mut improved = false;
            for d in dirs {
                let p = best + d * step;
                if (p - center).abs().max_element() > self.step {
                    continue;
                }
                let f = self.free_radius(p, reach);
                if f > r {
                    (best, r, improved) = (p, f, true);
                }
            }
            if !improved {
                step *= 0.5;
                if step < self.step * 0.125 {
                    break;
                }
            }
        }
        Sphere::new(best, r)
    }
}
