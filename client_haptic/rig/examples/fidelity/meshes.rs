//! The mesh scenes: a tool mesh pressed into an object mesh at a random point of its surface, judged
//! against a Monte Carlo reference computed another way than collette does (exact point containment,
//! `collette::shape::Solid`): `--samples` stratified points in the box the overlap can occupy give the
//! overlap's volume and centroid; the tool's surface points inside the object give the force's
//! direction, −∂V/∂t = −∫ n dA over the tool's surface inside the object (the way that shrinks the
//! overlap fastest; on a plane, the plane's normal).

use glam::{Quat, Vec3};
use haptic_common::Pose;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use collette::TriMesh;
use collette::shape::Solid;

use crate::{Dice, Exact, Shape};

/// A mesh, its tree and grid, its exact inside, and points on its surface.
pub struct MeshShape {
    pub shape: Shape,
    solid: Solid,
    mesh: TriMesh,
    /// Cumulative triangle areas (to pick surface points by area).
    area_cdf: Vec<f32>,
    /// Points on the surface, uniform by area, with the outward normal (the mesh's frame).
    surface: Vec<(Vec3, Vec3)>,
}

impl MeshShape {
    /// `mesh` with `surface_samples` points on its surface; `voxels` for its solid's grid.
    pub fn new(mesh: TriMesh, shape: Shape, voxels: usize, surface_samples: usize, dice: &mut Dice) -> Self {
        let solid = Solid::new(&mesh, voxels);
        let mut total = 0.0;
        let area_cdf = mesh
            .triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.vertices()[i as usize]);
                total += 0.5 * (b - a).cross(c - a).length();
                total
            })
            .collect();
        let mut m = Self { shape, solid, mesh, area_cdf, surface: Vec::new() };
        m.surface = (0..surface_samples).map(|_| m.surface_point(dice)).collect();
        m
    }

    fn area(&self) -> f32 {
        self.area_cdf.last().copied().unwrap_or(0.0)
    }

    /// A point on the surface, uniform by area, and the outward normal there (its triangle's, turned
    /// outward by the solid: the bunny's file winds its triangles the other way).
    pub fn surface_point(&self, dice: &mut Dice) -> (Vec3, Vec3) {
        let pick = dice.roll() * self.area();
        let i = self.area_cdf.partition_point(|&a| a < pick).min(self.area_cdf.len() - 1);
        let [a, b, c] = self.mesh.triangles()[i].map(|k| self.mesh.vertices()[k as usize]);
        let (mut u, mut v) = (dice.roll(), dice.roll());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let p = a + (b - a) * u + (c - a) * v;
        let n = (b - a).cross(c - a).normalize_or_zero();
        let step = 1e-3 * self.mesh.aabb().extents().max_element();
        (p, if self.solid.contains(p + n * step) { -n } else { n })
    }
}

/// The tool (`tool`) turned by `turn` and pressed `depth` into `object` at its surface point `p` with
/// outward normal `n`: its deepest point along −n lies `depth` under the tangent plane at `p`. The
/// pose, and the Monte Carlo reference (None when the overlap is empty, or the tool is sunk whole).
pub fn press(
    tool: &MeshShape,
    object: &MeshShape,
    turn: Quat,
    (p, n): (Vec3, Vec3),
    depth: f32,
    samples: usize,
    dice: &mut Dice,
) -> Option<(Pose, Exact)> {
    let support = tool.mesh.vertices().iter().map(|v| (turn * *v).dot(-n)).fold(f32::MIN, f32::max);
    let pose = Pose::new(p + n * (support - depth), turn);
    // The overlap lies above the plane `depth` under `p` (the tool does) and, but for an object that
    // rises over its tangent plane, below `p`'s plane; look up to `top` above it, and further when the
    // overlap reaches that high.
    let mut top = depth.max(0.002);
    for _ in 0..4 {
        match reference(tool, object, &pose, p, n, depth, top, samples, dice) {
            Reach::Inside(exact) => return Some((pose, exact)),
            Reach::Empty => return None,
            Reach::Higher => top *= 2.0,
        }
    }
    None
}

enum Reach {
    Inside(Exact),
    Empty,
    Higher,
}

/// The reference in the slab from `depth` under `p`'s tangent plane to `top` over it.
#[allow(clippy::too_many_arguments)]
fn reference(
    tool: &MeshShape,
    object: &MeshShape,
    pose: &Pose,
    p: Vec3,
    n: Vec3,
    depth: f32,
    top: f32,
    samples: usize,
    dice: &mut Dice,
) -> Reach {
    let (t1, t2) = n.any_orthonormal_pair();
    let height = |x: Vec3| (x - p).dot(n);
    // The tool's surface in the slab bounds the tool's part in it sideways.
    let in_slab: Vec<(Vec3, Vec3)> = tool
        .surface
        .iter()
        .map(|&(x, normal)| (pose.transform_point(x), pose.rotation * normal))
        .filter(|&(x, _)| height(x) <= top)
        .collect();
    if in_slab.is_empty() {
        return Reach::Empty;
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for (x, _) in &in_slab {
        let q = Vec3::new((*x - p).dot(t1), (*x - p).dot(t2), 0.0);
        (lo, hi) = (lo.min(q), hi.max(q));
    }
    let margin = 2e-4;
    let (lo, hi) = (lo - Vec3::splat(margin), hi + Vec3::splat(margin));
    let size = Vec3::new(hi.x - lo.x, hi.y - lo.y, top + depth);
    // Stratified: one jittered point per cell of a grid over the box.
    let cell = (size.x * size.y * size.z / samples as f32).cbrt();
    let cells = [size.x, size.y, size.z].map(|s| (s / cell).ceil().max(1.0) as usize);
    let seed: u64 = dice.0.random();
    let inverse = pose.inverse();
    // One generator per layer of cells (its own stream of the seed), so that the parallel sampling is
    // the same on every run.
    let (hits, sum, high) = (0..cells[2])
        .into_par_iter()
        .map(|z| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(z as u64);
            let (mut hits, mut sum, mut high) = (0u64, glam::DVec3::ZERO, false);
            for y in 0..cells[1] {
                for x in 0..cells[0] {
                    let j = Vec3::new(rng.random(), rng.random(), rng.random());
                    let local = (Vec3::new(x as f32, y as f32, z as f32) + j) * cell;
                    let (a, b, h) = (lo.x + local.x, lo.y + local.y, local.z - depth);
                    let w = p + t1 * a + t2 * b + n * h;
                    if h <= top && tool.solid.contains(inverse.transform_point(w)) && object.solid.contains(w) {
                        hits += 1;
                        sum += w.as_dvec3();
                        high |= h > 0.9 * top;
                    }
                }
            }
            (hits, sum, high)
        })
        .reduce(|| (0, glam::DVec3::ZERO, false), |a, b| (a.0 + b.0, a.1 + b.1, a.2 || b.2));
    if hits == 0 {
        return Reach::Empty;
    }
    if high {
        return Reach::Higher;
    }
    // Each point stands for its cell (the cells cover the box and a little more).
    let volume = hits as f32 * cell.powi(3);
    let centroid = (sum / hits as f64).as_vec3();
    // −∂V/∂t: the tool's outward normals where its surface is inside the object.
    let share = tool.area() / tool.surface.len() as f32;
    let pull: Vec3 = in_slab
        .par_iter()
        .filter(|(x, _)| object.solid.contains(*x))
        .map(|(_, normal)| *normal * share)
        .reduce(|| Vec3::ZERO, |a, b| a + b);
    let normal = (-pull).normalize_or_zero();
    // A tool inside the object all but a sliver has no way out that shrinks the overlap: its outward
    // normals sum to nothing, and no force direction is right or wrong.
    if normal == Vec3::ZERO || volume as f64 >= 0.95 * tool.solid.volume() {
        return Reach::Empty;
    }
    Reach::Inside(Exact { volume, normal, centroid })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{cap_centroid, cap_volume};

    fn mesh_shape(buffers: (Vec<Vec3>, Vec<[u32; 3]>), dice: &mut Dice) -> MeshShape {
        let mesh = TriMesh::new(buffers.0, buffers.1).expect("mesh");
        let (tree, _) = collette::build(&mesh, &collette::BuildOptions::spheres(100), &mut |_| {}).expect("tree");
        let grid = collette::SignedDistanceGrid::new(&mesh, 16).expect("grid");
        let shell = collette::SurfaceShell::new(&mesh, 0.005).expect("shell");
        let shape = Shape { tree: std::sync::Arc::new(tree), grid, shell };
        MeshShape::new(mesh, shape, 32, 100_000, dice)
    }

    #[test]
    fn the_monte_carlo_reference_of_a_ball_pressed_into_a_box_is_its_cap() {
        // A 1 cm ball pressed 3 mm into the top face of a 6 cm box, through the face's middle: the
        // overlap is a cap of height 3 mm, pushed straight up.
        let mut dice = Dice(<ChaCha8Rng as SeedableRng>::seed_from_u64(3));
        let ball = mesh_shape(collette::shape::uv_sphere_buffers(0.01, 64, 128), &mut dice);
        let cube = mesh_shape(collette::shape::box_buffers(Vec3::splat(0.03)), &mut dice);
        let (p, n) = (Vec3::new(0.002, 0.03, -0.003), Vec3::Y);
        let d = 0.003;
        let (pose, exact) = press(&ball, &cube, Quat::IDENTITY, (p, n), d, 200_000, &mut dice).expect("an overlap");
        assert!((pose.translation.y - (0.03 + 0.01 - d)).abs() < 2e-4, "the ball's bottom 3 mm in: {pose:?}");
        // The ball's mesh is a polyhedron inside the sphere: its cap is a little smaller.
        let cap = cap_volume(0.01, d);
        assert!((exact.volume / cap - 1.0).abs() < 0.03, "volume {} against the cap's {cap}", exact.volume);
        let centroid_y = pose.translation.y - cap_centroid(0.01, d);
        assert!((exact.centroid.y - centroid_y).abs() < 1e-4, "centroid {} against {centroid_y}", exact.centroid);
        assert!(exact.normal.angle_between(Vec3::Y).to_degrees() < 2.0, "pushed up: {}", exact.normal);
    }
}
