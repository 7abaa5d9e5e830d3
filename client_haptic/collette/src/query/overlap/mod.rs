//! Overlap of two Inner Sphere Trees: exact (every overlapping leaf pair) and time-budgeted (anytime).
//!
//! Inner spheres of one object never overlap each other, so the summed lens volumes are exactly the
//! overlap volume of the two packings (a lower bound of the objects' intersection volume).

mod affine;
mod batch;
mod coherent;
mod engine;
mod result;
mod sink;

pub use coherent::{CoherenceStats, CoherentOverlap};
pub use result::{Budget, OverlapResult};

use crate::partitioning::InnerSphereTree;
use crate::query::QueryWorkspace;
use engine::Engine;
use glam::{Affine3A, Vec3};
use haptic_common::{ContactSet, Pose};
use sink::{Contacts, VolumeOnly};

/// Total overlap volume of `a` at `pose_a` and `b` at `pose_b` (exact, no contacts reported).
pub fn overlap_volume(
    a: &InnerSphereTree,
    pose_a: &Pose,
    b: &InnerSphereTree,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
) -> OverlapResult {
    let mut engine = Engine::new(a, b, pose_a.relative_to(pose_b), Budget::Unlimited, true, VolumeOnly);
    engine.run_depth_first(ws);
    engine.result
}

/// Every overlapping leaf pair of `a` and `b` as world-frame contacts in `out` (cleared first), plus
/// the total volume (also stored in `out.total_volume`). Normals point from B towards A.
///
/// Pairs beyond `out`'s capacity still count in the volume; `out.truncated` is then set.
pub fn overlap(
    a: &InnerSphereTree,
    pose_a: &Pose,
    b: &InnerSphereTree,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
    out: &mut ContactSet,
) -> OverlapResult {
    run(a, pose_a, b, pose_b, Budget::Unlimited, false, ws, out)
}

/// Anytime overlap: refines breadth-first until `budget` runs out, then estimates every node pair not
/// yet refined from its bounding spheres' lens scaled by both nodes' fill ratios (summed leaf volume /
/// bound volume). Estimated pairs are reported as contacts too, so forces stay continuous.
///
/// A node lying wholly inside one leaf sphere of the other tree is reported as one contact carrying
/// the node's summed volume (exact volume, centroid at the node's bound centre, normal from the sphere
/// centre to it): with `Budget::Unlimited` the total volume is exact, with far fewer pairs to visit.
pub fn overlap_budgeted(
    a: &InnerSphereTree,
    pose_a: &Pose,
    b: &InnerSphereTree,
    pose_b: &Pose,
    budget: Budget,
    ws: &mut QueryWorkspace,
    out: &mut ContactSet,
) -> OverlapResult {
    run(a, pose_a, b, pose_b, budget, true, ws, out)
}

#[allow(clippy::too_many_arguments)]
fn run(
    a: &InnerSphereTree,
    pose_a: &Pose,
    b: &InnerSphereTree,
    pose_b: &Pose,
    budget: Budget,
    aggregate: bool,
    ws: &mut QueryWorkspace,
    out: &mut ContactSet,
) -> OverlapResult {
    out.clear();
    let to_world = Affine3A::from_rotation_translation(pose_a.rotation, pose_a.translation);
    let sink = Contacts::new(to_world, fallback_normal(a, b, pose_a, pose_b), out);
    let mut engine = Engine::new(a, b, pose_a.relative_to(pose_b), budget, aggregate, sink);
    match budget {
        Budget::Unlimited => engine.run_depth_first(ws),
        _ => engine.run_breadth_first(ws),
    }
    let result = engine.result;
    out.total_volume = result.total_volume;
    out.estimated_volume = result.estimated_volume;
    out.truncated |= !result.complete;
    result
}

/// Normal used when two sphere centres coincide: from B's root centre to A's, else +Y.
fn fallback_normal(a: &InnerSphereTree, b: &InnerSphereTree, pose_a: &Pose, pose_b: &Pose) -> Vec3 {
    let d = pose_a.transform_point(a.root().bound.center) - pose_b.transform_point(b.root().bound.center);
    d.try_normalize().unwrap_or(Vec3::Y)
}

#[cfg(test)]
mod tests;
