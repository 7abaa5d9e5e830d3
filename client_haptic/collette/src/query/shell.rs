//! Overlap of a tool's surface (its [`SurfaceShell`]) with a touched object's signed distance grid.
//!
//! You need this module when the force against an object with a surface grid should be exact on flat
//! faces at any depth, down to a tenth of a millimetre and a box's corner: a tool's inner spheres stop
//! short of its surface (so [`overlap_field`](crate::overlap_field) misses or overshoots the first
//! tenths of a millimetre), while its surface does not.
//!
//! With φ the object's distance (positive inside, `|∇φ| = 1`) and `n` the tool's outward normal, the
//! divergence theorem on the field `φ∇φ` over the overlap gives
//! `V = ∫_{tool's surface inside} φ (∇φ·n) dA − ∫_{overlap} φ Δφ dV`: each piece of the tool's surface
//! inside the object adds the column between it and the object's surface. Over each triangle of the
//! shell φ is taken linear (its corners' distances), the triangle clipped where φ > 0 and the column
//! integrated exactly, its centroid too; the second term is taken per column with the distance's
//! Laplacian at the leaf (first order in depth over the surface's radius of curvature). On a flat face
//! the volume, its centroid and its normal are exact at any depth.

use crate::query::QueryWorkspace;
use crate::query::overlap::{Budget, OverlapResult};
use crate::shape::{ShellNode, SignedDistanceGrid, SurfaceShell};
use glam::Vec3;
use haptic_common::{Contact, ContactSet, Pose};
use std::time::Instant;

/// Overlap of the tool A (its `shell` at `pose_a`) with the object B (its distance grid `b` at
/// `pose_b`): the volume and one world-frame contact per leaf of the shell with surface inside B (at
/// the centroid of its columns, the normal out of B: the direction that pushes the tool out). The
/// contacts' volumes are scaled so that their push (Σ volume × normal) has the overlap's volume as its
/// magnitude, the penalty's convention.
///
/// In the result `leaf_pairs` counts the shell's triangles inside B and `node_pairs` the shell's nodes
/// visited. Contacts beyond `out`'s capacity still count in the volume; `out.truncated` is then set.
pub fn overlap_shell(
    shell: &SurfaceShell,
    pose_a: &Pose,
    b: &SignedDistanceGrid,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
    out: &mut ContactSet,
) -> OverlapResult {
    overlap_shell_budgeted(shell, pose_a, b, pose_b, Budget::Unlimited, ws, out)
}

/// [`overlap_shell`] that stops when `budget` runs out: the nodes not visited are left out of the
/// volume and the contacts, and `complete` is false.
pub fn overlap_shell_budgeted(
    shell: &SurfaceShell,
    pose_a: &Pose,
    b: &SignedDistanceGrid,
    pose_b: &Pose,
    budget: Budget,
    ws: &mut QueryWorkspace,
    out: &mut ContactSet,
) -> OverlapResult {
    out.clear();
    let a_in_b = pose_b.relative_to(pose_a);
    let nodes = shell.nodes();
    let stack = &mut ws.nodes;
    stack.clear();
    stack.push(0);
    let mut result = OverlapResult { complete: true, ..OverlapResult::default() };
    let mut until_clock = 0u32;
    // The contacts' push, before its scaling.
    let mut push = Vec3::ZERO;
    // The node whose subtree gathers into one contact while the stack stays above `group_floor`.
    let group_radius = GROUP_EDGES * shell.max_edge();
    let (mut group, mut group_floor) = (Group::default(), None);
    let mut emit = |group: &mut Group, result: &mut OverlapResult, push: &mut Vec3| {
        if let Some(contact) = group.contact() {
            result.total_volume += group.volume;
            let world = Contact {
                point: pose_b.transform_point(contact.point),
                normal: pose_b.transform_vector(contact.normal),
                ..contact
            };
            if out.push(world) {
                *push += world.normal * world.volume;
            }
        }
        *group = Group::default();
    };
    while let Some(n) = stack.pop() {
        let spent = match budget {
            Budget::Unlimited => false,
            Budget::NodePairs(max) => result.node_pairs >= max,
            Budget::Deadline(deadline) => {
                until_clock = if until_clock == 0 { CLOCK_STRIDE } else { until_clock - 1 };
                until_clock == CLOCK_STRIDE && Instant::now() >= deadline
            }
        };
        if spent {
            result.complete = false;
            stack.clear();
            break;
        }
        result.node_pairs += 1;
        let node = nodes[n as usize];
        if group_floor.is_none() && node.radius <= group_radius {
            group_floor = Some(stack.len());
        }
        let center = a_in_b.transform_point(node.center);
        let f = b.distance(center);
        // No point of the node reaches inside: the interpolated distance rises at most its steepest
        // slope per unit moved.
        let outside = f + SignedDistanceGrid::STEEPEST * node.radius <= 0.0
            || (f + node.radius <= 0.0 && f + b.steepest_slope(center, node.radius) * node.radius <= 0.0);
        if !outside && node.count == 0 {
            stack.push(node.first);
            stack.push(node.first + 1);
            continue;
        }
        if !outside {
            measure_leaf(shell, node, &a_in_b, b, center, &mut group, &mut result);
        }
        // A node outside any group is its own; a group ends when its subtree is done.
        if group_floor.is_none_or(|floor| stack.len() <= floor) {
            group_floor = None;
            emit(&mut group, &mut result, &mut push);
        }
    }
    emit(&mut group, &mut result, &mut push);
    // The push's magnitude is the overlap's volume: on a flat face it is already (every column's normal
    // is the face's); on a curved one the columns' normals spread, and the push is scaled back up.
    let magnitude = push.length();
    if result.total_volume > 0.0 && magnitude > 0.0 {
        let scale = result.total_volume / magnitude;
        for contact in out.as_mut_slice() {
            contact.volume *= scale;
        }
    }
    result.total_volume = result.total_volume.max(0.0);
    out.total_volume = result.total_volume;
    out.truncated |= !result.complete;
    result
}

/// Nodes visited between two looks at the clock.
const CLOCK_STRIDE: u32 = 16;

/// A node of at most this many of the shell's longest edges in radius gathers its subtree into one
/// contact (about a contact per 4 mm of surface for a shell of 0.5 mm edges: a whole sphere's cap at
/// a centimetre's depth in a few hundred).
const GROUP_EDGES: f32 = 8.0;

/// Adds the columns under the triangles of leaf `node` (centre `center` in B's frame) to `group`.
fn measure_leaf(
    shell: &SurfaceShell,
    node: ShellNode,
    a_in_b: &Pose,
    b: &SignedDistanceGrid,
    center: Vec3,
    group: &mut Group,
    result: &mut OverlapResult,
) {
    let mut laplacian = None;
    for tri in &shell.triangles()[node.first as usize..(node.first + node.count) as usize] {
        let p = tri.map(|v| a_in_b.transform_point(v));
        let (mut phi, mut gradient) = ([0.0f32; 3], Vec3::ZERO);
        for (i, &q) in p.iter().enumerate() {
            let (d, g) = b.distance_and_gradient(q);
            phi[i] = d;
            gradient += g;
        }
        if phi.iter().all(|&d| d <= 0.0) {
            continue;
        }
        let (Some(n), Some(g)) = ((p[1] - p[0]).cross(p[2] - p[0]).try_normalize(), gradient.try_normalize()) else {
            continue;
        };
        let laplacian = *laplacian.get_or_insert_with(|| laplacian_at(b, center));
        result.leaf_pairs += 1;
        group.add(Column::of(p, phi), g, g.dot(n), laplacian);
    }
}

/// The distance's Laplacian at `p` (B's frame), from second differences one voxel apart.
fn laplacian_at(b: &SignedDistanceGrid, p: Vec3) -> f32 {
    let h = b.voxel_size();
    let sum: f32 =
        [Vec3::X, Vec3::Y, Vec3::Z].iter().map(|&axis| b.distance(p + axis * h) + b.distance(p - axis * h)).sum();
    (sum - 6.0 * b.distance(p)) / (h * h)
}

/// The integrals of one triangle's part inside B (φ > 0, φ linear between its corners): its area-weighted
/// depth `∫φ dA`, depth-weighted position `∫x φ dA` and `∫φ² dA`.
#[derive(Default)]
struct Column {
    depth: f32,
    moment: Vec3,
    depth_squared: f32,
    deepest: f32,
}

impl Column {
    /// The part of triangle `p` (B's frame) whose corners lie `phi` deep (positive inside) where φ > 0.
    fn of(p: [Vec3; 3], phi: [f32; 3]) -> Self {
        // Clipped by the line φ = 0: at most four corners.
        let mut corners = [(Vec3::ZERO, 0.0f32); 4];
        let mut k = 0;
        for i in 0..3 {
            let j = (i + 1) % 3;
            if phi[i] > 0.0 {
                corners[k] = (p[i], phi[i]);
                k += 1;
            }
            if (phi[i] > 0.0) != (phi[j] > 0.0) {
                let t = phi[i] / (phi[i] - phi[j]);
                corners[k] = (p[i] + (p[j] - p[i]) * t, 0.0);
                k += 1;
            }
        }
        let mut column = Column { deepest: phi.iter().copied().fold(0.0, f32::max), ..Column::default() };
        // A fan of triangles; over each, ∫f = A·Σfᵢ/3 and ∫f·g = A/12·(Σfᵢgᵢ + Σfᵢ·Σgᵢ) for linear f, g.
        for i in 1..k.saturating_sub(1) {
            let [(x0, d0), (x1, d1), (x2, d2)] = [corners[0], corners[i], corners[i + 1]];
            let area = 0.5 * (x1 - x0).cross(x2 - x0).length();
            let (sum_d, sum_x) = (d0 + d1 + d2, x0 + x1 + x2);
            column.depth += area * sum_d / 3.0;
            column.moment += area / 12.0 * (x0 * d0 + x1 * d1 + x2 * d2 + sum_x * sum_d);
            column.depth_squared += area / 12.0 * (d0 * d0 + d1 * d1 + d2 * d2 + sum_d * sum_d);
        }
        column
    }
}

/// The columns of one group of leaves: their volume, push and moment.
#[derive(Default)]
struct Group {
    /// Σ volume (signed: a piece of the tool's surface facing out of B takes its column away).
    volume: f32,
    /// Σ volume × B's outward normal.
    push: Vec3,
    /// Σ |volume| × the column's centroid, and Σ |volume|.
    weighted_point: Vec3,
    weight: f32,
    deepest: f32,
}

impl Group {
    /// Adds the column under one triangle: `g` the direction into B, `cos` its cosine with the
    /// triangle's outward normal, `laplacian` the distance's Laplacian there.
    fn add(&mut self, column: Column, g: Vec3, cos: f32, laplacian: f32) {
        if column.depth <= 0.0 {
            return;
        }
        // The curvature term, kept to half the column either way.
        let bend = (-0.5 * laplacian * column.depth_squared).clamp(-0.5 * column.depth, 0.5 * column.depth);
        let volume = cos * (column.depth + bend);
        // The column runs from the tool's surface out of B along −g: its centroid lies half the depth out.
        let centroid = (column.moment - g * (0.5 * column.depth_squared)) / column.depth;
        self.volume += volume;
        self.push -= g * volume;
        self.weighted_point += centroid * volume.abs();
        self.weight += volume.abs();
        self.deepest = self.deepest.max(column.deepest);
    }

    /// The group's contact in B's frame: its push as volume × normal, at its columns' centroid.
    fn contact(&self) -> Option<Contact> {
        let magnitude = self.push.length();
        (magnitude > 0.0 && self.weight > 0.0).then(|| Contact {
            point: self.weighted_point / self.weight,
            normal: self.push / magnitude,
            volume: magnitude,
            depth: self.deepest,
        })
    }
}
