//! Sphere weights: the share of the mesh each inner sphere stands for.
//!
//! The packing leaves gaps (between the spheres, and between the outermost spheres and the surface).
//! Every interior voxel centre in a gap is given to the sphere of least power distance `|p − c|² − r²`
//! (its cell of the spheres' power diagram: a point as far from a large sphere's surface as from a
//! small one's goes to the large one); a sphere's weight is then (its volume + its gap voxels' volume) /
//! its volume, the gap voxels scaled so that the shares add up to the exact mesh volume. A packing
//! allowed past the surface may hold more than the mesh (a ball's single sphere): then every weight is
//! mesh volume / packed volume, below 1.

use super::DistanceField;
use crate::partitioning::InnerSphereTree;
use glam::Vec3;
use rayon::prelude::*;

/// Weighs every sphere of `tree` (built from the mesh `field` samples) and updates its nodes.
pub(super) fn weigh(tree: &mut InnerSphereTree, field: &DistanceField) {
    let mesh = tree.mesh_volume() as f64;
    let packed: f64 = tree.spheres().iter().map(|s| s.volume() as f64).sum();
    if packed > mesh {
        let weights = vec![(mesh / packed) as f32; tree.spheres().len()];
        tree.set_weights(weights);
        return;
    }
    let covered = covered_voxels(tree, field);
    let owners: Vec<u32> = (0..field.distance.len())
        .into_par_iter()
        .filter(|&i| field.distance[i] > 0.0 && !covered[i])
        .map_init(Vec::new, |stack, i| {
            let (sphere, power) = least_power(tree, field.voxel_center(i), stack);
            if power > 0.0 { sphere } else { u32::MAX }
        })
        .filter(|&s| s != u32::MAX)
        .collect();
    let spheres = tree.spheres();
    let gap_volume = mesh - packed;
    let mut counts = vec![0u32; spheres.len()];
    for &s in &owners {
        counts[s as usize] += 1;
    }
    let per_voxel = if owners.is_empty() { 0.0 } else { gap_volume / owners.len() as f64 };
    let weights = spheres
        .iter()
        .zip(&counts)
        .map(|(s, &n)| {
            let v = s.volume() as f64;
            if v > 0.0 { (1.0 + n as f64 * per_voxel / v) as f32 } else { 1.0 }
        })
        .collect();
    tree.set_weights(weights);
}

/// Which voxel centres lie inside a sphere (each sphere marks the voxels of its box).
fn covered_voxels(tree: &InnerSphereTree, field: &DistanceField) -> Vec<bool> {
    let [nx, ny, nz] = field.dims;
    let mut covered = vec![false; nx * ny * nz];
    // Voxel centres are at origin + index × h: the first and one past the last index within [lo, hi].
    let first = |x: f32, n: usize| x.ceil().clamp(0.0, n as f32) as usize;
    let end = |x: f32, n: usize| (x.floor() + 1.0).clamp(0.0, n as f32) as usize;
    for s in tree.spheres() {
        let lo = (s.center - s.radius - field.origin) / field.voxel_size;
        let hi = (s.center + s.radius - field.origin) / field.voxel_size;
        let r2 = s.radius * s.radius;
        for k in first(lo.z, nz)..end(hi.z, nz) {
            for j in first(lo.y, ny)..end(hi.y, ny) {
                let row = (k * ny + j) * nx;
                for i in first(lo.x, nx)..end(hi.x, nx) {
                    if field.voxel_center(row + i).distance_squared(s.center) < r2 {
                        covered[row + i] = true;
                    }
                }
            }
        }
    }
    covered
}

/// The sphere of least power distance `|p − c|² − r²` from `p`, and that distance (negative inside
/// it): branch and bound over the hierarchy. A sphere inside a node's bound (centre C, radius R) has
/// `|c − C| = t ≤ R` and `r ≤ R − t`, so from `p` at `D = |p − C| ≥ R` its power distance is at least
/// `(D − t)² − (R − t)² ≥ (D − R)²`; from inside the bound, at least `−R²`.
fn least_power(tree: &InnerSphereTree, p: Vec3, stack: &mut Vec<u32>) -> (u32, f32) {
    let (nodes, spheres) = (tree.nodes(), tree.spheres());
    let mut best = (u32::MAX, f32::INFINITY);
    stack.clear();
    stack.push(0);
    while let Some(n) = stack.pop() {
        let node = &nodes[n as usize];
        let (d, r) = (p.distance(node.bound.center), node.bound.radius);
        let bound = if d >= r { (d - r) * (d - r) } else { -r * r };
        if bound >= best.1 {
            continue;
        }
        if node.leaf {
            for s in node.range() {
                let d = p.distance_squared(spheres[s].center) - spheres[s].radius * spheres[s].radius;
                if d < best.1 {
                    best = (s as u32, d);
                }
            }
        } else {
            stack.extend(node.range().map(|c| c as u32));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use crate::shape::{box_buffers, torus_buffers, uv_sphere_buffers};
    use crate::{BuildOptions, TriMesh, build};
    use glam::Vec3;

    #[test]
    fn the_weighted_spheres_stand_for_the_whole_mesh_and_each_at_least_for_itself() {
        for (v, t) in [box_buffers(Vec3::new(1.0, 0.5, 0.3)), torus_buffers(3.0, 1.0, 64, 32)] {
            let mesh = TriMesh::new(v, t).expect("valid");
            let (tree, report) = build(&mesh, &BuildOptions::spheres(500), &mut |_| {}).expect("builds");
            assert!(report.coverage < 0.95, "the packing leaves gaps: {}", report.coverage);
            let share = tree.mesh_share() as f64;
            assert!((share / report.mesh_volume - 1.0).abs() < 1e-3, "{share} vs {}", report.mesh_volume);
            assert!(tree.weights().iter().all(|&w| (1.0..50.0).contains(&w)), "weights >= 1");
            assert!(tree.weights().iter().any(|&w| w > 1.05), "gaps go to some spheres");
            tree.validate().expect("node shares add up");
            let plain = tree.unweighted();
            assert!((plain.mesh_share() - plain.packed_volume()).abs() < 1e-4 * plain.packed_volume());
        }
    }

    #[test]
    fn spheres_that_reach_past_the_surface_and_hold_more_than_the_mesh_are_weighed_down_to_it() {
        // A ball's packing is nearly its inscribed ball; grown past the facets it holds more than the mesh.
        let (v, t) = uv_sphere_buffers(1.0, 32, 64);
        let mesh = TriMesh::new(v, t).expect("valid");
        let (tree, report) = build(&mesh, &BuildOptions::spheres(200), &mut |_| {}).expect("builds");
        assert!(report.coverage > 1.0, "the packing holds more than the mesh: {}", report.coverage);
        let share = tree.mesh_share() as f64;
        assert!((share / report.mesh_volume - 1.0).abs() < 1e-3, "{share} vs {}", report.mesh_volume);
        let w = (report.mesh_volume / report.packed_volume) as f32;
        assert!(tree.weights().iter().all(|&x| (x - w).abs() < 1e-6), "every weight is {w}");
        tree.validate().expect("node shares add up");
    }
}
