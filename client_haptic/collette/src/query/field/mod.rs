//! Overlap of a tool's Inner Sphere Tree with a touched object's signed distance grid.
//!
//! You need this module when the overlap volume must follow the touched object's real surface: two
//! packings meet with an error set by the coarser packing's hollows (a 1 cm gem against the 10k-sphere
//! bunny: 0.94–1.07 of the true volume from p5 to p95), while the tool's spheres measured against the
//! object's distance give 0.99–1.01 (docs/collette.md, *Volume accuracy*). Each inner sphere of the
//! tool counts the part of it on the inner side of the surface: the cap cut by the tangent plane at the
//! interpolated distance, corrected for the surface's curvature by the distance's Laplacian over the
//! sphere (six more samples), times the sphere's weight. A node whose bound lies inside (or outside)
//! the object by more than the interpolation's error counts whole (or not at all) without descending;
//! its leaves would give the same, so the volume stays continuous as the tool moves.
//!
//! It suits a tool much smaller than the object it touches; for objects of similar size two trees
//! ([`overlap_budgeted`](crate::overlap_budgeted)) are closer, and faster.

use crate::partitioning::InnerSphereTree;
use crate::query::QueryWorkspace;
use crate::query::overlap::{Budget, OverlapResult};
use crate::shape::{SignedDistanceGrid, cap_moment, cap_volume, lens_volume, sphere_volume};
use glam::Vec3;
use haptic_common::{Contact, ContactSet, Pose};

/// Overlap of tree `a` at `pose_a` with the object B at `pose_b` — its tree `b` and its distance grid
/// `b_grid`, built from the same mesh: the volume (exact up to the grid's interpolation and the caps'
/// curvature term; B's packing stands in where B's surface bends within one of A's spheres) and one
/// world-frame contact per node or sphere of `a` inside B (normals from B towards A: the direction that
/// pushes the tool out).
///
/// In the result `leaf_pairs` counts A's spheres reaching into B, `aggregated_pairs` A's nodes counted
/// whole and `node_pairs` A's nodes visited. Contacts beyond `out`'s capacity still count in the
/// volume; `out.truncated` is then set.
pub fn overlap_field(
    a: &InnerSphereTree,
    pose_a: &Pose,
    b: &InnerSphereTree,
    b_grid: &SignedDistanceGrid,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
    out: &mut ContactSet,
) -> OverlapResult {
    overlap_field_budgeted(a, pose_a, b, b_grid, pose_b, Budget::Unlimited, ws, out)
}

/// [`overlap_field`] that stops descending when `budget` runs out and estimates each node it has not
/// visited from its bound: the node's mesh share times the part of its bounding sphere inside B (the cap
/// of the tangent plane at its centre's distance), reported as a contact too so forces stay continuous.
/// The estimate is in `estimated_volume`; `complete` is false.
#[allow(clippy::too_many_arguments)]
pub fn overlap_field_budgeted(
    a: &InnerSphereTree,
    pose_a: &Pose,
    b: &InnerSphereTree,
    b_grid: &SignedDistanceGrid,
    pose_b: &Pose,
    budget: Budget,
    ws: &mut QueryWorkspace,
    out: &mut ContactSet,
) -> OverlapResult {
    out.clear();
    let result = descend(a, pose_a, (b, b_grid), pose_b, budget, ws, Some((out, pose_b)));
    out.total_volume = result.total_volume;
    out.estimated_volume = result.estimated_volume;
    out.truncated |= !result.complete;
    result
}

/// The volume of [`overlap_field`] alone (no contacts).
pub fn overlap_field_volume(
    a: &InnerSphereTree,
    pose_a: &Pose,
    b: &InnerSphereTree,
    b_grid: &SignedDistanceGrid,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
) -> OverlapResult {
    descend(a, pose_a, (b, b_grid), pose_b, Budget::Unlimited, ws, None)
}

fn descend(
    a: &InnerSphereTree,
    pose_a: &Pose,
    (b_tree, b): (&InnerSphereTree, &SignedDistanceGrid),
    pose_b: &Pose,
    budget: Budget,
    ws: &mut QueryWorkspace,
    mut out: Option<(&mut ContactSet, &Pose)>,
) -> OverlapResult {
    let a_in_b = pose_b.relative_to(pose_a);
    let margin = 2.0 * b.interpolation_error();
    let (nodes, spheres, weights) = (a.nodes(), a.spheres(), a.weights());
    let mut result = OverlapResult { complete: true, ..OverlapResult::default() };
    // `into_b`: the direction into B (the distance's gradient, or a cut sphere's own direction).
    let mut push = |point: Vec3, into_b: Vec3, volume: f32, depth: f32| {
        if let Some((set, to_world)) = out.as_mut() {
            let normal = -into_b.try_normalize().unwrap_or(Vec3::Y);
            set.push(Contact {
                point: to_world.transform_point(point),
                normal: to_world.transform_vector(normal),
                volume,
                depth,
            });
        }
    };
    // Unlimited: depth-first on a stack. Budgeted: breadth-first through the ring while it has room (so
    // a budget leaves the tree evenly refined), depth-first beyond.
    let QueryWorkspace { nodes: stack, ring, stack: b_stack, .. } = ws;
    let breadth_first = !matches!(budget, Budget::Unlimited);
    stack.clear();
    let mut frontier = Frontier { ring, head: 0, queued: 0, breadth_first };
    frontier.push(0, stack);
    let mut until_clock = 0;
    while let Some(n) = frontier.pop(stack) {
        let node = &nodes[n as usize];
        if budget.spent(result.node_pairs, &mut until_clock) {
            // This node and every one still queued: estimated from its bound.
            result.complete = false;
            let waiting = (0..frontier.queued).map(|i| frontier.ring[(frontier.head + i) % frontier.ring.len()].0);
            for n in std::iter::once(n).chain(waiting).chain(stack.drain(..)) {
                let node = &nodes[n as usize];
                let center = a_in_b.transform_point(node.bound.center);
                let r = node.bound.radius;
                let (f, into_b) = b.distance_and_gradient(center);
                let h = (r + f).clamp(0.0, 2.0 * r);
                let volume = node.mesh_share * cap_volume(r, h) / sphere_volume(r).max(f32::MIN_POSITIVE);
                if volume > 0.0 {
                    result.total_volume += volume;
                    result.estimated_volume += volume;
                    result.estimated_pairs += 1;
                    push(center, into_b, volume, h);
                }
            }
            break;
        }
        result.node_pairs += 1;
        let center = a_in_b.transform_point(node.bound.center);
        let (f, into_b) = b.distance_and_gradient(center);
        let r = node.bound.radius;
        // Either bound keeps every leaf on the same side as its node (so the volume is the leaves'):
        // the interpolation's error twice, or the interpolant's steepest slope `L` across the node (a
        // leaf sphere of radius `s` lies within `r − s` of the centre, so `|f| ≥ max(L, 1) r` keeps it
        // whole or out). `L` is at most √3; where `|f|` falls between, the grid's slope pyramid tells
        // the node's own, about 1 near a smooth surface.
        let mut margin = margin.min((SignedDistanceGrid::STEEPEST - 1.0) * r);
        if f.abs() >= r && f.abs() < r + margin {
            margin = margin.min((b.steepest_slope(center, r) - 1.0).max(0.0) * r);
        }
        if f <= -r - margin {
            continue;
        }
        if f >= r + margin {
            result.total_volume += node.mesh_share;
            result.aggregated_pairs += 1;
            push(center, into_b, node.mesh_share, f + r);
            continue;
        }
        if !node.leaf {
            for child in node.range() {
                frontier.push(child as u32, stack);
            }
            continue;
        }
        for s in node.range() {
            let sphere = spheres[s];
            let c = a_in_b.transform_point(sphere.center);
            if let Some(part) = Part::of((b_tree, b), c, sphere.radius, b_stack) {
                let volume = part.volume * weights[s];
                result.total_volume += volume;
                result.leaf_pairs += 1;
                push(part.centroid, part.into_b, volume, part.depth);
            }
        }
    }
    result
}

/// The nodes still to visit: in the ring first (first in, first out), on the stack when the ring is
/// full or the query is depth-first.
struct Frontier<'w> {
    ring: &'w mut [(u32, u32)],
    head: usize,
    queued: usize,
    breadth_first: bool,
}

impl Frontier<'_> {
    #[inline]
    fn push(&mut self, n: u32, stack: &mut Vec<u32>) {
        if self.breadth_first && self.queued < self.ring.len() {
            self.ring[(self.head + self.queued) % self.ring.len()] = (n, 0);
            self.queued += 1;
        } else {
            stack.push(n);
        }
    }

    #[inline]
    fn pop(&mut self, stack: &mut Vec<u32>) -> Option<u32> {
        if self.queued == 0 {
            return stack.pop();
        }
        let n = self.ring[self.head].0;
        (self.head, self.queued) = ((self.head + 1) % self.ring.len(), self.queued - 1);
        Some(n)
    }
}

/// The part of one inner sphere inside the object.
struct Part {
    /// Its volume (the sphere's own, before its weight).
    volume: f32,
    /// Its centroid, B's frame.
    centroid: Vec3,
    /// The direction into the object (not normalized): where the surface cuts the sphere, or the
    /// distance's gradient at the centre of a sphere wholly inside.
    into_b: Vec3,
    /// How deep the sphere reaches into the object: radius + the centre's distance.
    depth: f32,
}

impl Part {
    /// The part of the sphere (`c` in B's frame, radius `r`) inside B, `None` when there is none.
    #[inline]
    fn of(
        (tree, b): (&InnerSphereTree, &SignedDistanceGrid),
        c: Vec3,
        r: f32,
        stack: &mut Vec<(u32, u32)>,
    ) -> Option<Self> {
        let (f, gradient) = b.distance_and_gradient(c);
        if f <= -r {
            return None;
        }
        if f >= r {
            return Some(Self { volume: sphere_volume(r), centroid: c, into_b: gradient, depth: f + r });
        }
        let cut = Cut::of(b, c, r, (f, gradient));
        let h = r + cut.distance;
        let cap = cap_volume(r, h);
        let mut volume = cap;
        let packed = cut.packed_share();
        if packed > 0.0 {
            volume += packed * (packed_part(tree, c, r, stack) - volume);
        }
        if volume <= 0.0 {
            return None;
        }
        // The cap's centroid, towards B.
        let offset = if cap > 0.0 { cap_moment(r, h) / cap } else { r };
        let into_b = cut.into_b;
        Some(Self { volume, centroid: c + into_b.normalize_or_zero() * offset, into_b, depth: f + r })
    }
}

/// Where B's surface cuts one sphere of A.
struct Cut {
    /// The cutting plane's signed distance from the centre (positive with the centre inside),
    /// corrected for curvature.
    distance: f32,
    /// The direction into B (not normalized).
    into_b: Vec3,
    /// The curvature correction over the radius, before it fades: how far the surface inside the
    /// sphere is from a plane.
    bend: f32,
    /// `(1 − (f/r)²)²`.
    fade: f32,
}

impl Cut {
    /// Where the surface cuts the sphere whose centre lies at interpolated distance `f` (|f| < r), with
    /// the distance's `gradient` there: the cutting plane's signed distance from the centre (positive
    /// with the centre inside), corrected for curvature, and the direction into the object.
    ///
    /// Six samples at `±a` along the axes give the gradient and the Laplacian of the distance. A
    /// ball's part on one side of a surface of mean curvature `κ` is, to first order in `κ`, the cap of
    /// the tangent plane moved by `r²/8 × Δφ` (with `Δφ ≈ −2κ` for a distance); the mean of the six
    /// samples is `f + a²/6 × Δφ`. The correction fades as `(1 − (f/r)²)²`, so a sphere's volume meets
    /// its whole volume (and zero) with a zero slope where it enters (leaves) the object.
    #[inline]
    fn of(b: &SignedDistanceGrid, c: Vec3, r: f32, (f, gradient): (f32, Vec3)) -> Self {
        let a = 0.866 * r;
        let px = b.distance(c + Vec3::X * a);
        let nx = b.distance(c - Vec3::X * a);
        let py = b.distance(c + Vec3::Y * a);
        let ny = b.distance(c - Vec3::Y * a);
        let pz = b.distance(c + Vec3::Z * a);
        let nz = b.distance(c - Vec3::Z * a);
        let laplacian = (px + nx + py + ny + pz + nz - 6.0 * f) / (a * a);
        let t = f / r;
        let fade = (1.0 - t * t) * (1.0 - t * t);
        let mut into_b = Vec3::new(px - nx, py - ny, pz - nz);
        if into_b == Vec3::ZERO {
            into_b = gradient;
        }
        let correction = r * r * 0.125 * laplacian;
        Self { distance: (f + correction * fade).clamp(-r, r), into_b, bend: correction.abs() / r, fade }
    }

    /// How much of the sphere's volume to take from B's packing instead of the cut: none while the
    /// surface inside the sphere is nearly flat, all of it (where the sphere straddles the surface)
    /// once the curvature term reaches [`BEND_PACKED`] of the radius: an edge, a corner or a wall
    /// thinner than the sphere, which a curved cap cannot follow.
    #[inline]
    fn packed_share(&self) -> f32 {
        let t = ((self.bend - BEND_FLAT) / (BEND_PACKED - BEND_FLAT)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t) * self.fade
    }
}

/// Below this curvature term (over the radius) a sphere's part inside B is its curved cap alone.
const BEND_FLAT: f32 = 0.1;
/// From this curvature term (over the radius) on, it is the sphere's overlap with B's packing.
const BEND_PACKED: f32 = 0.3;

/// The sphere (`c` in B's frame, radius `r`)'s overlap with B's weighted packing: its lens with each of
/// B's spheres times their weights, B's nodes inside the sphere counted whole.
fn packed_part(tree: &InnerSphereTree, c: Vec3, r: f32, stack: &mut Vec<(u32, u32)>) -> f32 {
    let (nodes, spheres, weights) = (tree.nodes(), tree.spheres(), tree.weights());
    let mut volume = 0.0;
    stack.clear();
    stack.push((0, 0));
    while let Some((n, _)) = stack.pop() {
        let node = &nodes[n as usize];
        let d = node.bound.center.distance(c);
        if d >= r + node.bound.radius {
            continue;
        }
        if d + node.bound.radius <= r {
            volume += node.mesh_share;
            continue;
        }
        if node.leaf {
            for s in node.range() {
                volume += lens_volume(r, spheres[s].radius, spheres[s].center.distance(c)) * weights[s];
            }
        } else {
            stack.extend(node.range().map(|child| (child as u32, 0)));
        }
    }
    volume
}

#[cfg(test)]
mod tests;
