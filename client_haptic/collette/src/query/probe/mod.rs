//! Point and small-sphere probes (3-DOF tools): penetration depth and normal against one tree.

use crate::partitioning::for_each_leaf_in_sphere;
use crate::query::QueryWorkspace;
use crate::shape::lens;
use glam::Vec3;
use haptic_common::{Contact, ContactSet, Pose};

/// The deepest penetration of a probe into a tree's spheres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeHit {
    /// Penetration depth `r_sphere + r_probe − distance` of the deepest inner sphere, world units.
    pub depth: f32,
    /// Unit world normal from that sphere's centre towards the probe (the direction to push the probe).
    pub normal: Vec3,
    /// World point on the inner sphere's surface below the probe centre.
    pub surface_point: Vec3,
    /// Inner spheres touched.
    pub touched: u32,
    /// Summed overlap volume with the touched spheres (0 for a point probe).
    pub volume: f32,
}

/// Calls `f` with every inner sphere of `tree` at `pose` that reaches within `radius` of the world point
/// `center`, as its world centre and radius: what a god-object proxy near `center` can meet (see
/// `forcecomp::proxy`). Allocation-free once `ws` has grown to the tree's depth.
pub fn spheres_near(
    tree: &crate::InnerSphereTree,
    pose: &Pose,
    center: Vec3,
    radius: f32,
    ws: &mut QueryWorkspace,
    mut f: impl FnMut(Vec3, f32),
) {
    let local = pose.inverse().transform_point(center);
    for_each_leaf_in_sphere(tree, local, radius.max(0.0), &mut ws.nodes, |_, s| {
        f(pose.transform_point(s.center), s.radius);
    });
}

/// Probes `tree` at `pose` with a ball of `radius` (0 for a point) centred at world `center`.
///
/// Returns `None` when the probe touches no inner sphere. When `out` is given it is cleared and filled
/// with one contact per touched sphere (world frame, normals towards the probe).
pub fn probe(
    tree: &crate::InnerSphereTree,
    pose: &Pose,
    center: Vec3,
    radius: f32,
    ws: &mut QueryWorkspace,
    mut out: Option<&mut ContactSet>,
) -> Option<ProbeHit> {
    if let Some(o) = out.as_deref_mut() {
        o.clear();
    }
    let local = pose.inverse().transform_point(center);
    let radius = radius.max(0.0);
    let mut best: Option<ProbeHit> = None;
    let (mut touched, mut volume) = (0u32, 0.0f32);
    for_each_leaf_in_sphere(tree, local, radius, &mut ws.nodes, |_, s| {
        let delta = local - s.center;
        let d = delta.length();
        let n_local = if d > 1e-12 { delta / d } else { Vec3::Y };
        let depth = s.radius + radius - d;
        let v = if radius > 0.0 { lens(s.center, s.radius, local, radius).map_or(0.0, |l| l.volume) } else { 0.0 };
        touched += 1;
        volume += v;
        let normal = pose.transform_vector(n_local);
        let surface_point = pose.transform_point(s.center + n_local * s.radius);
        if let Some(o) = out.as_deref_mut() {
            o.push(Contact { point: surface_point, normal, volume: v, depth });
            o.total_volume += v;
        }
        if best.is_none_or(|b| depth > b.depth) {
            best = Some(ProbeHit { depth, normal, surface_point, touched: 0, volume: 0.0 });
        }
    });
    best.map(|b| ProbeHit { touched, volume, ..b })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{InnerSphereTree, Sphere};

    #[test]
    fn a_point_inside_a_sphere_reports_depth_and_outward_normal() {
        let t =
            InnerSphereTree::from_spheres(vec![Sphere::new(Vec3::ZERO, 1.0), Sphere::new(Vec3::X * 3.0, 1.0)], 10.0);
        let pose = Pose::from_translation(Vec3::Z * 5.0);
        let mut ws = QueryWorkspace::new();
        let hit = probe(&t, &pose, Vec3::new(0.0, 0.0, 5.75), 0.0, &mut ws, None).expect("inside");
        assert!((hit.depth - 0.25).abs() < 1e-5);
        assert!((hit.normal - Vec3::Z).length() < 1e-5);
        assert!((hit.surface_point - Vec3::Z * 6.0).length() < 1e-5);
        assert!(probe(&t, &pose, Vec3::new(1.5, 0.0, 5.0), 0.0, &mut ws, None).is_none());
        let mut set = ContactSet::new();
        let hit = probe(&t, &pose, Vec3::new(1.5, 0.0, 5.0), 0.6, &mut ws, Some(&mut set)).expect("touches both");
        assert_eq!(hit.touched, 2);
        assert_eq!(set.len(), 2);
        assert!(hit.volume > 0.0);
    }
}
