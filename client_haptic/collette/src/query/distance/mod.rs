//! Separation distance between two trees that do not overlap (branch and bound on the hierarchy).

use crate::partitioning::InnerSphereTree;
use crate::query::QueryWorkspace;
use glam::Vec3;
use haptic_common::Pose;

/// Result of a separation query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Separation {
    /// Some inner spheres overlap.
    Overlapping,
    /// The packings are apart.
    Separated {
        /// Smallest gap between an inner sphere of A and one of B (an upper bound of the objects' gap,
        /// short by at most the unpacked margin), world units.
        distance: f32,
        /// Closest point on A's inner sphere, world frame.
        point_a: Vec3,
        /// Closest point on B's inner sphere, world frame.
        point_b: Vec3,
    },
}

/// Separation of `a` at `pose_a` and `b` at `pose_b`.
pub fn separation(
    a: &InnerSphereTree,
    pose_a: &Pose,
    b: &InnerSphereTree,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
) -> Separation {
    let pos12 = pose_a.relative_to(pose_b);
    let gap = |ca: Vec3, ra: f32, cb: Vec3, rb: f32| ca.distance(cb) - ra - rb;
    let mut best = f32::INFINITY;
    let mut best_pair = (Vec3::ZERO, 0.0f32, Vec3::ZERO, 0.0f32);
    ws.stack.clear();
    ws.stack.push((0, 0));
    while let Some((ia, ib)) = ws.stack.pop() {
        let (na, nb) = (&a.nodes[ia as usize], &b.nodes[ib as usize]);
        let cb = pos12.transform_point(nb.bound.center);
        if gap(na.bound.center, na.bound.radius, cb, nb.bound.radius) >= best {
            continue;
        }
        if na.leaf && nb.leaf {
            for sb in &b.spheres[nb.range()] {
                let cb = pos12.transform_point(sb.center);
                for sa in &a.spheres[na.range()] {
                    let g = gap(sa.center, sa.radius, cb, sb.radius);
                    if g < 0.0 {
                        return Separation::Overlapping;
                    }
                    if g < best {
                        best = g;
                        best_pair = (sa.center, sa.radius, cb, sb.radius);
                    }
                }
            }
            continue;
        }
        // Push children farthest first, so the nearest pair is explored first and tightens the bound.
        let mut kids = [(0u32, 0u32, 0.0f32); 4];
        let descend_a = nb.leaf || (!na.leaf && na.bound.radius >= nb.bound.radius);
        let n = if descend_a { na.count as usize } else { nb.count as usize };
        for (k, kid) in kids.iter_mut().enumerate().take(n) {
            let (ca, cb_) = if descend_a { (na.first + k as u32, ib) } else { (ia, nb.first + k as u32) };
            let (ma, mb) = (&a.nodes[ca as usize], &b.nodes[cb_ as usize]);
            *kid = (
                ca,
                cb_,
                gap(ma.bound.center, ma.bound.radius, pos12.transform_point(mb.bound.center), mb.bound.radius),
            );
        }
        kids[..n].sort_unstable_by(|x, y| y.2.total_cmp(&x.2));
        ws.stack.extend(kids[..n].iter().filter(|k| k.2 < best).map(|k| (k.0, k.1)));
    }
    if !best.is_finite() {
        return Separation::Separated { distance: f32::INFINITY, point_a: Vec3::ZERO, point_b: Vec3::ZERO };
    }
    let (ca, ra, cb, rb) = best_pair;
    let u = (cb - ca).try_normalize().unwrap_or(Vec3::X);
    Separation::Separated {
        distance: best,
        point_a: pose_a.transform_point(ca + u * ra),
        point_b: pose_a.transform_point(cb - u * rb),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Sphere;

    #[test]
    fn two_unit_balls_three_apart_are_separated_by_one() {
        let t = InnerSphereTree::from_spheres(vec![Sphere::new(Vec3::ZERO, 1.0)], 4.19);
        let mut ws = QueryWorkspace::new();
        let s = separation(&t, &Pose::IDENTITY, &t, &Pose::from_translation(Vec3::X * 3.0), &mut ws);
        let Separation::Separated { distance, point_a, point_b } = s else { panic!("apart") };
        assert!((distance - 1.0).abs() < 1e-5);
        assert!((point_a - Vec3::X).length() < 1e-5 && (point_b - Vec3::X * 2.0).length() < 1e-5);
        let s = separation(&t, &Pose::IDENTITY, &t, &Pose::from_translation(Vec3::X * 1.5), &mut ws);
        assert_eq!(s, Separation::Overlapping);
    }
}
