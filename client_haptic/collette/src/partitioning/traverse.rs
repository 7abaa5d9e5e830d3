//! Visiting the tree: leaves near a ball (used by probes and renderers).

use super::InnerSphereTree;
use crate::shape::Sphere;
use glam::Vec3;

/// Calls `f(sphere_index, sphere)` for every leaf sphere overlapping the ball (`center`, `radius`),
/// in the tree's local frame; `stack` is a caller-owned scratch buffer (cleared here).
pub fn for_each_leaf_in_sphere(
    tree: &InnerSphereTree,
    center: Vec3,
    radius: f32,
    stack: &mut Vec<u32>,
    mut f: impl FnMut(usize, &Sphere),
) {
    stack.clear();
    stack.push(0);
    while let Some(n) = stack.pop() {
        let node = &tree.nodes[n as usize];
        let r = node.bound.radius + radius;
        if node.bound.center.distance_squared(center) >= r * r {
            continue;
        }
        if node.leaf {
            for i in node.range() {
                let s = &tree.spheres[i];
                let r = s.radius + radius;
                if s.center.distance_squared(center) < r * r {
                    f(i, s);
                }
            }
        } else {
            stack.extend(node.range().map(|c| c as u32));
        }
    }
}
