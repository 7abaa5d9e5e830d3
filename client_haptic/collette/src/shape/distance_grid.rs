//! A closed mesh's signed distance, sampled on a regular grid and interpolated trilinearly.
//!
//! You need this module when a tool's overlap with an object should follow the object's surface
//! rather than its sphere packing: [`overlap_field`](crate::query::overlap_field) measures each of the
//! tool's inner spheres against this grid (see docs/collette.md, *Volume accuracy*).

use crate::error::BuildError;
use crate::packing::{MAX_VOXELS, to_parry_oriented};
use crate::shape::TriMesh;
use glam::{Vec3, Vec4, Vec4Swizzles};
use parry3d::query::PointQuery;
use rayon::prelude::*;

/// Signed distance to a closed mesh's surface (positive inside, metres of the mesh) at the centres of
/// a regular grid that reaches [`SignedDistanceGrid::MARGIN_VOXELS`] past the mesh's box, each with
/// the distance's gradient there (central differences of the neighbouring values), so that one
/// interpolation gives both.
#[derive(Clone, Debug)]
pub struct SignedDistanceGrid {
    origin: Vec3,
    /// The last grid point (largest corner).
    last: Vec3,
    /// The largest cell index along each axis (dims − 2), as floats.
    last_cell: Vec3,
    voxel: f32,
    inv_voxel: f32,
    dims: [usize; 3],
    /// Per grid point: the distance, then its gradient (x, y, z).
    values: Vec<Vec4>,
}

impl SignedDistanceGrid {
    /// Voxels of grid around the mesh's box on every side.
    pub const MARGIN_VOXELS: usize = 2;
    /// Largest accepted resolution (voxels along the longest side of the mesh's box).
    pub const MAX_RESOLUTION: usize = 1024;

    /// Samples `mesh` with `resolution` voxels along the longest side of its box (150 matches the
    /// packing grid of a 10k-sphere tree). Each value is exact (parry's projection with pseudo-normals).
    pub fn new(mesh: &TriMesh, resolution: usize) -> Result<Self, BuildError> {
        if !(2..=Self::MAX_RESOLUTION).contains(&resolution) {
            return Err(BuildError::InvalidOption(format!(
                "distance grid resolution {resolution} is outside 2..={}",
                Self::MAX_RESOLUTION
            )));
        }
        let bounds = mesh.aabb();
        let ext = bounds.extents();
        let voxel = ext.max_element() / resolution as f32;
        let margin = Self::MARGIN_VOXELS as f32 * voxel;
        let dims = [0, 1, 2].map(|a| ((ext[a] + 2.0 * margin) / voxel).ceil() as usize + 1);
        let count: f64 = dims.iter().map(|&d| d as f64).product();
        if count > MAX_VOXELS as f64 {
            return Err(BuildError::InvalidOption(format!(
                "distance grid resolution {resolution} needs {count:.3e} voxels (at most {MAX_VOXELS})"
            )));
        }
        let origin = bounds.min - Vec3::splat(margin);
        let parry = to_parry_oriented(mesh);
        let mut distances = vec![0.0f32; dims[0] * dims[1] * dims[2]];
        distances.par_chunks_mut(dims[0]).enumerate().for_each(|(row, out)| {
            let (j, k) = (row % dims[1], row / dims[1]);
            for (i, v) in out.iter_mut().enumerate() {
                let p = origin + Vec3::new(i as f32, j as f32, k as f32) * voxel;
                let q = parry3d::math::Vector::new(p.x, p.y, p.z);
                let proj = parry.project_local_point(q, false);
                let d = (proj.point - q).length();
                *v = if proj.is_inside { d } else { -d };
            }
        });
        let values = gradients(&distances, dims, voxel);
        let last = origin + Vec3::new((dims[0] - 1) as f32, (dims[1] - 1) as f32, (dims[2] - 1) as f32) * voxel;
        let last_cell = Vec3::new((dims[0] - 2) as f32, (dims[1] - 2) as f32, (dims[2] - 2) as f32);
        Ok(Self { origin, last, last_cell, voxel, inv_voxel: 1.0 / voxel, dims, values })
    }

    /// Edge length of a voxel (mesh units).
    pub fn voxel_size(&self) -> f32 {
        self.voxel
    }

    /// Voxels along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Bytes the grid holds (16 per grid point).
    pub fn memory_bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<Vec4>()
    }

    /// How far [`SignedDistanceGrid::distance`] may be from the true signed distance inside the grid:
    /// the interpolation is a convex combination of exact values at corners at most half a voxel
    /// diagonal away, and the distance changes by at most the distance moved.
    pub fn interpolation_error(&self) -> f32 {
        self.voxel * 3f32.sqrt() * 0.5
    }

    /// Interpolated signed distance at `p` (mesh frame; positive inside). Outside the grid: the value
    /// at the nearest point of the grid minus the distance to it.
    #[inline]
    pub fn distance(&self, p: Vec3) -> f32 {
        self.distance_and_gradient(p).0
    }

    /// Gradient of the distance at `p`, interpolated from the grid points' central differences: it
    /// points into the mesh (length about 1 near the surface; outside the grid, towards it) and, unlike
    /// the interpolant's own gradient, changes continuously across the cells' faces, so normals built on
    /// it do not jump.
    #[inline]
    pub fn gradient(&self, p: Vec3) -> Vec3 {
        self.distance_and_gradient(p).1
    }

    /// [`distance`](Self::distance) and [`gradient`](Self::gradient) at `p`, from one interpolation.
    #[inline]
    pub fn distance_and_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let q = p.clamp(self.origin, self.last);
        let g = (q - self.origin) * self.inv_voxel;
        // The last cell also takes the grid's far faces.
        let cell = Vec3::new(whole(g.x), whole(g.y), whole(g.z)).min(self.last_cell);
        let t = (g - cell).clamp(Vec3::ZERO, Vec3::ONE);
        let (i, j, k) = (cell.x as usize, cell.y as usize, cell.z as usize);
        let [c000, c100, c010, c110, c001, c101, c011, c111] = self.corners((k * self.dims[1] + j) * self.dims[0] + i);
        let x00 = c000 + (c100 - c000) * t.x;
        let x10 = c010 + (c110 - c010) * t.x;
        let x01 = c001 + (c101 - c001) * t.x;
        let x11 = c011 + (c111 - c011) * t.x;
        let y0 = x00 + (x10 - x00) * t.y;
        let y1 = x01 + (x11 - x01) * t.y;
        let v = y0 + (y1 - y0) * t.z;
        if q == p {
            return (v.x, v.yzw());
        }
        // Outside: the distance falls by the way to the grid; along each axis `p` was clamped on, the
        // gradient is that way's, along the others the grid's.
        let out = q - p;
        let away = out.length();
        let towards = out / away;
        let clamped = out.cmpne(Vec3::ZERO);
        (v.x - away, Vec3::select(clamped, towards, v.yzw()))
    }

    #[inline]
    fn corners(&self, cell: usize) -> [Vec4; 8] {
        let (sx, sy) = (self.dims[0], self.dims[0] * self.dims[1]);
        // One bounds check for the eight corners.
        let v = &self.values[cell..cell + sy + sx + 2];
        [v[0], v[1], v[sx], v[sx + 1], v[sy], v[sy + 1], v[sy + sx], v[sy + sx + 1]]
    }
}

/// Each grid point's distance with its gradient: central differences one voxel either side, one-sided
/// on the grid's faces.
fn gradients(distances: &[f32], dims: [usize; 3], voxel: f32) -> Vec<Vec4> {
    let strides = [1, dims[0], dims[0] * dims[1]];
    let mut values = vec![Vec4::ZERO; distances.len()];
    values.par_chunks_mut(dims[0]).enumerate().for_each(|(row, out)| {
        let (j, k) = (row % dims[1], row / dims[1]);
        for (i, v) in out.iter_mut().enumerate() {
            let at = [i, j, k];
            let index = row * dims[0] + i;
            let slope = |axis: usize| {
                let (below, above) = (at[axis] > 0, at[axis] + 1 < dims[axis]);
                let lo = if below { distances[index - strides[axis]] } else { distances[index] };
                let hi = if above { distances[index + strides[axis]] } else { distances[index] };
                let span = (below as u32 + above as u32).max(1) as f32 * voxel;
                (hi - lo) / span
            };
            *v = Vec4::new(distances[index], slope(0), slope(1), slope(2));
        }
    });
    values
}

/// The whole part of a non-negative `x`, without libm's `floorf` (which the baseline x86-64 calls: it
/// has no rounding instruction).
#[inline]
fn whole(x: f32) -> f32 {
    x as u32 as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::{box_buffers, uv_sphere_buffers};

    #[test]
    fn the_grid_gives_a_boxs_signed_distance_inside_and_out() {
        let (v, t) = box_buffers(Vec3::new(1.0, 0.5, 0.5));
        let grid = SignedDistanceGrid::new(&TriMesh::new(v, t).expect("valid"), 40).expect("builds");
        for (p, want) in [
            (Vec3::ZERO, 0.5),
            (Vec3::new(0.9, 0.0, 0.0), 0.1),
            (Vec3::new(0.0, 0.0, 0.6), -0.1),
            (Vec3::new(0.0, 0.3, 0.0), 0.2),
            (Vec3::new(3.0, 0.0, 0.0), -2.0),
        ] {
            let d = grid.distance(p);
            assert!((d - want).abs() <= grid.interpolation_error() + 1e-5, "{p}: {d} vs {want}");
        }
        let g = grid.gradient(Vec3::new(0.0, 0.0, 0.45));
        assert!((g - Vec3::NEG_Z).length() < 1e-3, "gradient into the box: {g}");
        let far = grid.gradient(Vec3::new(5.0, 0.0, 0.0));
        assert!((far - Vec3::NEG_X).length() < 1e-3, "outside the grid, towards it: {far}");
        // Continuous across a cell face (x = −0.9) near the box's edge, where the nearest face changes
        // from one cell to the next and the interpolant's own slope jumps.
        let (below, above) = (Vec3::new(-0.9 - 1e-5, 0.0, 0.41), Vec3::new(-0.9 + 1e-5, 0.0, 0.41));
        assert!((grid.gradient(below) - grid.gradient(above)).length() < 1e-2, "no jump at a face");
    }

    #[test]
    fn near_a_balls_surface_the_distance_is_close_to_exact() {
        let (v, t) = uv_sphere_buffers(1.0, 64, 128);
        let grid = SignedDistanceGrid::new(&TriMesh::new(v, t).expect("valid"), 64).expect("builds");
        for i in 0..200 {
            let dir = Vec3::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos(), (i as f32 * 0.13).sin()).normalize();
            let r = 0.9 + 0.2 * (i as f32 / 200.0);
            // The facetted ball's surface is within 0.0004 of the unit sphere at this tessellation.
            let d = grid.distance(dir * r);
            assert!((d - (1.0 - r)).abs() < 0.004, "at radius {r}: {d}");
        }
    }

    #[test]
    fn bad_resolutions_are_refused_with_their_value() {
        let (v, t) = box_buffers(Vec3::ONE);
        let mesh = TriMesh::new(v, t).expect("valid");
        for bad in [0, 1, 5000] {
            let why = SignedDistanceGrid::new(&mesh, bad).expect_err("refused").to_string();
            assert!(why.contains(&bad.to_string()) && why.contains("resolution"), "{why}");
        }
    }
}
