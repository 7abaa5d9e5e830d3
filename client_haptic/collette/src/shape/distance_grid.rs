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
    /// The interpolant's steepest slope, per cell (level 0) and over blocks of 2ᵏ cells a side (level
    /// k), in hundredths rounded up.
    slopes: Vec<SlopeLevel>,
}

/// The steepest slopes over blocks of one size.
#[derive(Clone, Debug)]
struct SlopeLevel {
    dims: [usize; 3],
    hundredths: Vec<u8>,
}

impl SignedDistanceGrid {
    /// Voxels of grid around the mesh's box on every side.
    pub const MARGIN_VOXELS: usize = 2;
    /// Largest accepted resolution (voxels along the longest side of the mesh's box).
    pub const MAX_RESOLUTION: usize = 1024;

    /// The box the grid covers (the mesh's box and the margin), in the mesh's frame.
    pub fn bounds(&self) -> crate::bounding_volume::Aabb {
        crate::bounding_volume::Aabb::new(self.origin, self.last)
    }

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
        let slopes = slope_pyramid(&distances, dims, voxel);
        let last = origin + Vec3::new((dims[0] - 1) as f32, (dims[1] - 1) as f32, (dims[2] - 1) as f32) * voxel;
        let last_cell = Vec3::new((dims[0] - 2) as f32, (dims[1] - 2) as f32, (dims[2] - 2) as f32);
        Ok(Self { origin, last, last_cell, voxel, inv_voxel: 1.0 / voxel, dims, values, slopes })
    }

    /// Edge length of a voxel (mesh units).
    pub fn voxel_size(&self) -> f32 {
        self.voxel
    }

    /// Voxels along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Bytes the grid holds (16 per grid point and about 1.15 per cell for the slopes).
    pub fn memory_bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<Vec4>() + self.slopes.iter().map(|l| l.hundredths.len()).sum::<usize>()
    }

    /// An upper bound of the interpolated distance's slope (`|∇ distance|`) anywhere within `radius` of
    /// `center`: the steepest of the cells that box covers, from the slope pyramid (at most eight
    /// blocks). Where the box leaves the grid, [`SignedDistanceGrid::STEEPEST`]. About 1 near a smooth
    /// surface; up to √3 where the nearest part of the surface changes (the medial axis).
    pub fn steepest_slope(&self, center: Vec3, radius: f32) -> f32 {
        let (lo, hi) = (center - Vec3::splat(radius), center + Vec3::splat(radius));
        if !(lo.cmpge(self.origin).all() && hi.cmple(self.last).all()) {
            return Self::STEEPEST;
        }
        let cell = |p: Vec3| {
            let g = ((p - self.origin) * self.inv_voxel).min(self.last_cell);
            [g.x as usize, g.y as usize, g.z as usize]
        };
        let (lo, hi) = (cell(lo), cell(hi));
        let span = (0..3).map(|a| hi[a] - lo[a]).max().unwrap_or(0);
        // The smallest level at which the box spans at most two blocks a side.
        let mut level = 0;
        while (span >> level) > 1 && level + 1 < self.slopes.len() {
            level += 1;
        }
        let l = &self.slopes[level];
        // Within the level: a cell index below `cells` shifted by `level` is below `ceil(cells / 2ᵏ)`.
        let (lo, hi) = (lo.map(|c| c >> level), hi.map(|c| c >> level));
        let mut steepest = 0u8;
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    steepest = steepest.max(l.hundredths[(k * l.dims[1] + j) * l.dims[0] + i]);
                }
            }
        }
        steepest as f32 * 0.01
    }

    /// The steepest slope the interpolated distance can have: each axis's difference of two exact
    /// distances one voxel apart is at most a voxel (and outside the grid the distance falls by 1 per
    /// unit away, beside the grid's own slope along its faces).
    pub const STEEPEST: f32 = 1.732_050_8;

    /// How far [`SignedDistanceGrid::distance`] may be from the true signed distance inside the grid:
    /// the interpolation is a convex combination of exact values at corners at most half a voxel
    /// diagonal away, and the distance changes by at most the distance moved.
    pub fn interpolation_error(&self) -> f32 {
        self.voxel * 3f32.sqrt() * 0.5
    }

    /// Interpolated signed distance at `p` (mesh frame; positive inside). Outside the grid: the tangent
    /// plane at the nearest point of the grid, extrapolated (the value there plus the gradient's share of
    /// the way: exact for a flat face, and for a curved one seen at an angle far closer than the value
    /// less the whole way, which made a big sphere beside a ball miss it; it falls with the way out and
    /// never reaches the inside, since the mesh lies inside the grid).
    #[inline]
    pub fn distance(&self, p: Vec3) -> f32 {
        self.distance_and_gradient(p).0
    }

    /// Gradient of the distance at `p`, interpolated from the grid points' central differences: it
    /// points into the mesh (length about 1 near the surface; outside the grid, the nearest grid
    /// point's) and, unlike
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
        // Outside: the tangent plane at the nearest grid point. The gradient there points at the mesh,
        // which lies inside the grid, so it has no share along the way out: the distance only falls.
        let gradient = v.yzw();
        (v.x + gradient.dot(p - q).min(0.0), gradient)
    }

    #[inline]
    fn corners(&self, cell: usize) -> [Vec4; 8] {
        let (sx, sy) = (self.dims[0], self.dims[0] * self.dims[1]);
        // One bounds check for the eight corners.
        let v = &self.values[cell..cell + sy + sx + 2];
        [v[0], v[1], v[sx], v[sx + 1], v[sy], v[sy + 1], v[sy + sx], v[sy + sx + 1]]
    }
}

/// The slope pyramid: per cell, the largest of the trilinear interpolant's gradient lengths at its eight
/// corners, which is the largest anywhere in it (each partial derivative is bilinear in the other two
/// coordinates and constant along its own, so `|∇f|²` is convex along every axis and peaks at a
/// corner); each level above keeps the largest of 2 × 2 × 2 blocks below, up to one block.
fn slope_pyramid(distances: &[f32], dims: [usize; 3], voxel: f32) -> Vec<SlopeLevel> {
    let cells = dims.map(|d| d - 1);
    let at = |i: usize, j: usize, k: usize| distances[(k * dims[1] + j) * dims[0] + i];
    let mut base = vec![0u8; cells[0] * cells[1] * cells[2]];
    base.par_chunks_mut(cells[0]).enumerate().for_each(|(row, out)| {
        let (j, k) = (row % cells[1], row / cells[1]);
        for (i, slope) in out.iter_mut().enumerate() {
            // The gradient at the cell's corner (a, b, c): each axis's edge difference through it.
            let corner = |a: usize, b: usize, c: usize| {
                let (x, y, z) = (i + a, j + b, k + c);
                Vec3::new(at(i + 1, y, z) - at(i, y, z), at(x, j + 1, z) - at(x, j, z), at(x, y, k + 1) - at(x, y, k))
                    .length()
            };
            let corners = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1)];
            let norm = corners.iter().map(|&(a, b, c)| corner(a, b, c)).fold(0.0, f32::max) / voxel;
            // Rounded up, so the bound stays a bound.
            *slope = (norm * 100.0).ceil().min(255.0) as u8;
        }
    });
    let mut levels = vec![SlopeLevel { dims: cells, hundredths: base }];
    while levels.last().is_some_and(|l| l.dims.iter().any(|&d| d > 1)) {
        let below = levels.last().expect("a level");
        let dims = below.dims.map(|d| d.div_ceil(2));
        let mut hundredths = vec![0u8; dims[0] * dims[1] * dims[2]];
        for k in 0..below.dims[2] {
            for j in 0..below.dims[1] {
                for i in 0..below.dims[0] {
                    let up = &mut hundredths[((k / 2) * dims[1] + j / 2) * dims[0] + i / 2];
                    *up = (*up).max(below.hundredths[(k * below.dims[1] + j) * below.dims[0] + i]);
                }
            }
        }
        levels.push(SlopeLevel { dims, hundredths });
    }
    levels
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
    fn the_slope_pyramid_bounds_the_interpolants_slope_and_is_about_one_near_a_face() {
        let (v, t) = uv_sphere_buffers(1.0, 32, 64);
        let grid = SignedDistanceGrid::new(&TriMesh::new(v, t).expect("valid"), 24).expect("builds");
        let h = 1e-3 * grid.voxel_size();
        let mut worst = 0.0f32;
        for i in 0..4000 {
            let u = i as f32;
            let center = Vec3::new((u * 0.37).sin(), (u * 0.61).cos(), (u * 0.13).sin()) * 1.1;
            let radius = grid.voxel_size() * (0.2 + 3.0 * (u * 0.71).sin().abs());
            let bound = grid.steepest_slope(center, radius);
            // The interpolant's own slope by differences much finer than a cell, at a point in the box.
            let p = center + Vec3::new((u * 1.3).sin(), (u * 1.7).cos(), (u * 2.9).sin()) * radius * 0.57;
            let slope = Vec3::new(
                grid.distance(p + Vec3::X * h) - grid.distance(p - Vec3::X * h),
                grid.distance(p + Vec3::Y * h) - grid.distance(p - Vec3::Y * h),
                grid.distance(p + Vec3::Z * h) - grid.distance(p - Vec3::Z * h),
            )
            .length()
                / (2.0 * h);
            assert!(slope <= bound + 0.02, "at {p}: slope {slope} above the bound {bound}");
            worst = worst.max(bound);
        }
        assert!(worst <= SignedDistanceGrid::STEEPEST + 1e-6, "{worst}");
        // By a face of a box, one cell across: the distance is a plane's, slope 1.
        let (v, t) = box_buffers(Vec3::ONE);
        let grid = SignedDistanceGrid::new(&TriMesh::new(v, t).expect("valid"), 40).expect("builds");
        let by_face = grid.steepest_slope(Vec3::new(0.0, 0.0, 0.99), 0.5 * grid.voxel_size());
        assert!((1.0..=1.011).contains(&by_face), "{by_face}");
        // Leaving the grid: the bound for anywhere.
        assert_eq!(grid.steepest_slope(Vec3::new(0.0, 0.0, 0.99), 10.0), SignedDistanceGrid::STEEPEST);
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
