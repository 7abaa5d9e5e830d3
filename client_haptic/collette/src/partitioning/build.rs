//! Top-down hierarchy construction: clustering weighted by sphere volume (at most 4 children per node).

use super::{InnerSphereTree, Node};
use crate::bounding_volume::enclosing_sphere;
use crate::shape::Sphere;

/// Maximum number of spheres in a leaf node.
pub const LEAF_SIZE: usize = 1;

impl InnerSphereTree {
    /// Builds the hierarchy over packed spheres (reordered so each leaf holds a contiguous range).
    ///
    /// Each node is split in two at the volume-weighted median along its axis of largest volume-weighted
    /// spread (the split index kept within the middle half so the tree stays balanced), twice per level,
    /// giving up to four children. Inner nodes store the sphere wrapping their leaves and their leaves'
    /// summed volume. Every sphere weighs 1 ([`InnerSphereTree::weights`]): `build` weighs them.
    pub fn from_spheres(spheres: Vec<Sphere>, mesh_volume: f32) -> Self {
        Self::from_spheres_in_leaves(spheres, mesh_volume, LEAF_SIZE)
    }

    /// [`InnerSphereTree::from_spheres`] with up to `leaf_size` spheres per leaf (trees from other
    /// builders, and tests of the queries' paths for them).
    pub(crate) fn from_spheres_in_leaves(mut spheres: Vec<Sphere>, mesh_volume: f32, leaf_size: usize) -> Self {
        let leaf_size = leaf_size.max(1);
        let mut nodes = vec![Node::default()];
        let mut work = vec![(0usize, 0usize, spheres.len())];
        while let Some((node, lo, hi)) = work.pop() {
            let slice = &spheres[lo..hi];
            let volume = slice.iter().map(|s| s.volume() as f64).sum::<f64>() as f32;
            let bound = enclosing_sphere(slice);
            if hi - lo <= leaf_size {
                nodes[node] =
                    Node { bound, volume, mesh_share: volume, first: lo as u32, count: (hi - lo) as u32, leaf: true };
                continue;
            }
            let mid = split(&mut spheres[lo..hi]) + lo;
            let mut parts = Vec::with_capacity(4);
            for (a, b) in [(lo, mid), (mid, hi)] {
                if b - a > 2 * leaf_size {
                    let m = split(&mut spheres[a..b]) + a;
                    parts.push((a, m));
                    parts.push((m, b));
                } else {
                    parts.push((a, b));
                }
            }
            let first = nodes.len();
            nodes.extend(parts.iter().map(|_| Node::default()));
            nodes[node] =
                Node { bound, volume, mesh_share: volume, first: first as u32, count: parts.len() as u32, leaf: false };
            for (i, &(a, b)) in parts.iter().enumerate().rev() {
                work.push((first + i, a, b));
            }
        }
        let weights = vec![1.0; spheres.len()];
        let mut tree = Self { spheres, weights, nodes, mesh_volume, blocks: Vec::new(), block_of: Vec::new() };
        tree.rebuild_blocks();
        tree
    }
}

/// Sorts `spheres` along the axis of largest volume-weighted spread and returns the split index.
fn split(spheres: &mut [Sphere]) -> usize {
    let n = spheres.len();
    let weight = |s: &Sphere| s.volume() as f64 + 1e-30;
    let total: f64 = spheres.iter().map(weight).sum();
    let mean = spheres.iter().map(|s| s.center.as_dvec3() * weight(s)).sum::<glam::DVec3>() / total;
    let var = spheres.iter().map(|s| (s.center.as_dvec3() - mean).powf(2.0) * weight(s)).sum::<glam::DVec3>();
    let axis = if var.x >= var.y && var.x >= var.z {
        0
    } else if var.y >= var.z {
        1
    } else {
        2
    };
    // Stable sort on the coordinate keeps the result deterministic for equal coordinates.
    spheres.sort_by(|a, b| a.center[axis].total_cmp(&b.center[axis]));
    let mut acc = 0.0;
    let mut mid = n / 2;
    for (i, s) in spheres.iter().enumerate() {
        acc += weight(s);
        if acc >= total * 0.5 {
            mid = i + 1;
            break;
        }
    }
    mid.clamp(n / 4, n - n / 4).clamp(1, n - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn line_of_spheres(n: usize) -> Vec<Sphere> {
        (0..n)
            .map(|i| Sphere::new(Vec3::new(i as f32, (i % 3) as f32 * 0.1, 0.0), 0.1 + (i % 5) as f32 * 0.05))
            .collect()
    }

    #[test]
    fn every_sphere_ends_in_exactly_one_leaf_and_volumes_add_up() {
        let t = InnerSphereTree::from_spheres(line_of_spheres(101), 100.0);
        t.validate().expect("valid tree");
        let total: f32 = t.spheres().iter().map(|s| s.volume()).sum();
        assert!((t.root().volume - total).abs() < 1e-3 * total);
        assert!(t.depth() < 12, "balanced: depth {}", t.depth());
    }

    #[test]
    fn a_single_sphere_is_a_leaf_root() {
        let t = InnerSphereTree::from_spheres(vec![Sphere::new(Vec3::ZERO, 1.0)], 5.0);
        assert!(t.root().leaf);
        assert_eq!(t.depth(), 1);
    }
}
