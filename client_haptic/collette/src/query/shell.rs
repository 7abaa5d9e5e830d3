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
//! shell φ is taken piecewise linear (its corners' distances, and its edges' middles from the cubic
//! through the ends' distances and slopes), the triangle clipped where φ > 0 and the column integrated
//! exactly, its centroid too; the second term is taken per column from the distance's Laplacian and
//! Hessian at the leaf (the column's cross-section to second order in its length: exact for a ball
//! and a cylinder). On a flat face the volume, its centroid and its normal are exact at any depth.
//! The push points the way out, `−∫ n dA` over the tool's surface inside (exact anywhere: beside an
//! edge of B the columns run to the side face and lean the push over). Past the middle of a part of B
//! thinner than the tool is deep a column runs to the far face: the volume is then too small (the
//! overlap taken as at least the columns' push); [`overlap_surfaces`](crate::overlap_surfaces) is
//! exact there.

use crate::query::QueryWorkspace;
use crate::query::overlap::{Budget, OverlapResult};
use crate::shape::{ShellNode, SignedDistanceGrid, SurfaceShell};
use glam::Vec3;
use haptic_common::{Contact, ContactSet, Pose};

/// Overlap of the tool A (its `shell` at `pose_a`) with the object B (its distance grid `b` at
/// `pose_b`): the volume and one world-frame contact per group of leaves with surface inside B (a
/// subtree about 8 of the shell's edges in radius; at the centroid of its columns, the normal out of B:
/// the direction that pushes the tool out). The contacts are turned together so that their push
/// (Σ volume × normal) points the way out that shrinks the overlap fastest (`−∫ n dA` over the tool's
/// surface inside B, exact whatever the depth), and their volumes scaled so that it has the overlap's
/// volume as its magnitude, the penalty's convention.
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
    // The contacts' push, before its scaling, and the way out: −∫ n dA over the tool's surface inside B.
    let mut push = Vec3::ZERO;
    let mut surface = Surface::default();
    // The node whose subtree gathers into one contact while the stack stays above `group_floor`.
    let group_radius = GROUP_EDGES * shell.max_edge();
    let (mut group, mut group_floor) = (Group::default(), None);
    let mut emit = |group: &mut Group, result: &mut OverlapResult, push: &mut Vec3, surface: &mut Surface| {
        surface.merge(&group.surface);
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
        if budget.spent(result.node_pairs, &mut until_clock) {
            result.complete = false;
            stack.clear();
            break;
        }
        result.node_pairs += 1;
        let node = nodes[n as usize];
        let center = a_in_b.transform_point(node.center);
        if group_floor.is_none() && node.radius <= group_radius {
            group_floor = Some(stack.len());
        }
        let f = b.distance(center);
        let outside = outside(b, center, node.radius, f);
        if !outside && node.count == 0 {
            stack.push(node.first);
            stack.push(node.first + 1);
            continue;
        }
        if !outside {
            measure_leaf(shell, node, &a_in_b, b, (center, f), &mut group, &mut result);
        }
        // A node outside any group is its own; a group ends when its subtree is done.
        if group_floor.is_none_or(|floor| stack.len() <= floor) {
            group_floor = None;
            emit(&mut group, &mut result, &mut push, &mut surface);
        }
    }
    emit(&mut group, &mut result, &mut push, &mut surface);
    // The push's direction is the way out (the columns' agrees on a face; past the middle of a part of B
    // thinner than the tool is deep a column runs to B's far face and points the push through it) and
    // its magnitude the overlap's volume: on a flat face it is already (every column's normal is the
    // face's); on a curved one the columns' normals spread, and the push is scaled back up.
    let magnitude = push.length();
    // Past the middle of a thin part a column measures to the far face and its signed volume falls (to
    // nothing or below), while its push (−g·(g·n)·φ, the same whichever face g comes from) holds up:
    // the overlap is at least the push.
    result.total_volume = result.total_volume.max(magnitude);
    if result.total_volume > 0.0 && magnitude > 0.0 {
        let scale = result.total_volume / magnitude;
        let turn = surface.way_out(pose_b).map(|way| glam::Quat::from_rotation_arc(push / magnitude, way));
        for contact in out.as_mut_slice() {
            contact.volume *= scale;
            if let Some(turn) = turn {
                contact.normal = turn * contact.normal;
            }
        }
    }
    result.total_volume = result.total_volume.max(0.0);
    out.total_volume = result.total_volume;
    out.truncated |= !result.complete;
    result
}

/// How far an edge's middle may lie off the line between its ends' distances for the triangle to be
/// taken as flat, m.
const FLAT_M: f32 = 1e-7;

/// A node of at most this many of the shell's longest edges in radius gathers its subtree into one
/// contact (about a contact per 4 mm of surface for a shell of 0.5 mm edges: a whole sphere's cap at
/// a centimetre's depth in a few hundred).
const GROUP_EDGES: f32 = 8.0;

/// Adds the columns under the triangles of leaf `node` (its centre in B's frame, and the distance there)
/// to `group`, with how the distance bends read at the leaf's centre the first time a column needs it
/// (read once per group instead, a few millimetres off, it was wrong enough on the bunny to put the
/// volume 5 % off at p50).
fn measure_leaf(
    shell: &SurfaceShell,
    node: ShellNode,
    a_in_b: &Pose,
    b: &SignedDistanceGrid,
    (center, f): (Vec3, f32),
    group: &mut Group,
    result: &mut OverlapResult,
) {
    let mut curvature = None;
    for (p, phi, gradients) in leaf_triangles(shell, &node, a_in_b, b) {
        let mut column = Column::default();
        if !inside_pieces(p, phi, gradients, |piece| column.add(piece)) {
            continue;
        }
        let gradient = gradients[0] + gradients[1] + gradients[2];
        let (Some(n), Some(g)) = ((p[1] - p[0]).cross(p[2] - p[0]).try_normalize(), gradient.try_normalize()) else {
            continue;
        };
        let curvature = *curvature.get_or_insert_with(|| curvature_at(b, center, f));
        result.leaf_pairs += 1;
        group.surface.add(n, column.area);
        group.add(column, g, g.dot(n), curvature);
    }
}

/// Whether no point within `radius` of `center` (the grid's frame; `f` the distance there) reaches
/// inside: the interpolated distance rises at most its steepest slope per unit moved (√3 first, the
/// slope pyramid's bound when that is not enough).
pub(super) fn outside(grid: &SignedDistanceGrid, center: Vec3, radius: f32, f: f32) -> bool {
    f + SignedDistanceGrid::STEEPEST * radius <= 0.0
        || (f + radius <= 0.0 && f + grid.steepest_slope(center, radius) * radius <= 0.0)
}

/// The triangles of leaf `node` in the grid's frame (`into_grid` maps the shell's frame there), each
/// with the distance and its gradient at its corners: every corner the leaf's triangles share read
/// once.
pub(super) fn leaf_triangles<'s>(
    shell: &'s SurfaceShell,
    node: &ShellNode,
    into_grid: &Pose,
    grid: &SignedDistanceGrid,
) -> impl Iterator<Item = ([Vec3; 3], [f32; 3], [Vec3; 3])> + 's {
    let (corners, corner_of) = shell.leaf(node);
    let mut read = [(Vec3::ZERO, 0.0f32, Vec3::ZERO); SurfaceShell::LEAF_CORNERS];
    for (slot, &corner) in read.iter_mut().zip(corners) {
        let q = into_grid.transform_point(corner);
        let (d, g) = grid.distance_and_gradient(q);
        *slot = (q, d, g);
    }
    corner_of.iter().map(move |local| {
        let [r0, r1, r2] = local.map(|k| read[k as usize]);
        ([r0.0, r1.0, r2.0], [r0.1, r1.1, r2.1], [r0.2, r1.2, r2.2])
    })
}

/// Hands `piece` the parts of triangle `p` where φ > 0 (each a triangle with φ at its corners, φ ≥ 0),
/// given φ and its gradient at the corners: φ piecewise linear over the four triangles of the corners
/// and the edges' middles (each middle's φ from the cubic through its ends' values and slopes along the
/// edge), or over the triangle itself where the middles lie on it (a flat face: a tenth of a micrometre
/// off at most). False when no part is inside.
pub(super) fn inside_pieces(
    p: [Vec3; 3],
    phi: [f32; 3],
    gradients: [Vec3; 3],
    mut piece: impl FnMut([(Vec3, f32); 3]),
) -> bool {
    let middle = |i: usize, j: usize| {
        let bend = (gradients[i] - gradients[j]).dot(p[j] - p[i]) * 0.125;
        ((p[i] + p[j]) * 0.5, 0.5 * (phi[i] + phi[j]) + bend)
    };
    let (m01, m12, m20) = (middle(0, 1), middle(1, 2), middle(2, 0));
    if phi.iter().chain([&m01.1, &m12.1, &m20.1]).all(|&d| d <= 0.0) {
        return false;
    }
    let (c0, c1, c2) = ((p[0], phi[0]), (p[1], phi[1]), (p[2], phi[2]));
    let straight = |m: (Vec3, f32), i: usize, j: usize| (m.1 - 0.5 * (phi[i] + phi[j])).abs() <= FLAT_M;
    if straight(m01, 0, 1) && straight(m12, 1, 2) && straight(m20, 2, 0) {
        clip([c0, c1, c2], &mut piece);
    } else {
        for part in [[c0, m01, m20], [m01, c1, m12], [m20, m12, c2], [m01, m12, m20]] {
            clip(part, &mut piece);
        }
    }
    true
}

/// Hands `piece` the part of a triangle (φ linear between its corners) where φ > 0, as a fan of
/// triangles.
fn clip(corners_phi: [(Vec3, f32); 3], piece: &mut impl FnMut([(Vec3, f32); 3])) {
    let (p, phi) = (corners_phi.map(|c| c.0), corners_phi.map(|c| c.1));
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
    for i in 1..k.saturating_sub(1) {
        piece([corners[0], corners[i], corners[i + 1]]);
    }
}

/// How the distance bends at `p` (B's frame; `f` the distance there), from six reads one voxel either
/// side along the axes: its Laplacian `Δφ` (second differences of the distance) and `σ₂`, the sum of the
/// Hessian's principal 2 × 2 minors (`(tr² − ‖H‖²)/2`, the Hessian from central differences of the
/// gradient): a column's cross-section at `s` out from its base is `1 − Δφ·s + σ₂·s²` of its base's
/// (for a ball of radius ρ, `(1 + s/ρ)²`; for a cylinder, `1 + s/ρ`).
fn curvature_at(b: &SignedDistanceGrid, p: Vec3, f: f32) -> (f32, f32) {
    let h = b.voxel_size();
    let (mut second, mut hessian) = (0.0, [Vec3::ZERO; 3]);
    for (i, axis) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
        let (up, g_up) = b.distance_and_gradient(p + axis * h);
        let (down, g_down) = b.distance_and_gradient(p - axis * h);
        second += up + down;
        hessian[i] = (g_up - g_down) / (2.0 * h);
    }
    let laplacian = (second - 6.0 * f) / (h * h);
    let trace = hessian[0].x + hessian[1].y + hessian[2].z;
    // ‖H‖² of the symmetrized Hessian.
    let (xy, xz, yz) =
        (0.5 * (hessian[0].y + hessian[1].x), 0.5 * (hessian[0].z + hessian[2].x), 0.5 * (hessian[1].z + hessian[2].y));
    let norm = hessian[0].x.powi(2) + hessian[1].y.powi(2) + hessian[2].z.powi(2) + 2.0 * (xy * xy + xz * xz + yz * yz);
    (laplacian, 0.5 * (trace * trace - norm))
}

/// The integrals over one triangle's part inside B (φ > 0, φ piecewise linear between its corners and
/// its edges' middles): `∫φ dA`, `∫x φ dA`, `∫φ² dA` and `∫φ³ dA`.
#[derive(Default)]
struct Column {
    depth: f32,
    moment: Vec3,
    depth_squared: f32,
    depth_cubed: f32,
    deepest: f32,
    area: f32,
}

impl Column {
    /// Adds a triangle inside B (its corners in B's frame, each with how deep it lies, φ linear
    /// between them): over it ∫f = A·Σfᵢ/3 and ∫f·g = A/12·(Σfᵢgᵢ + Σfᵢ·Σgᵢ) for linear f, g.
    fn add(&mut self, piece: [(Vec3, f32); 3]) {
        let [(x0, d0), (x1, d1), (x2, d2)] = piece;
        self.deepest = self.deepest.max(d0).max(d1).max(d2);
        let area = 0.5 * (x1 - x0).cross(x2 - x0).length();
        self.area += area;
        let (sum_d, sum_x) = (d0 + d1 + d2, x0 + x1 + x2);
        self.depth += area * sum_d / 3.0;
        self.moment += area / 12.0 * (x0 * d0 + x1 * d1 + x2 * d2 + sum_x * sum_d);
        self.depth_squared += area / 12.0 * (d0 * d0 + d1 * d1 + d2 * d2 + sum_d * sum_d);
        // ∫f³ = A/10·(Σfᵢ³ + Σ_{i≠j}fᵢ²fⱼ + f₀f₁f₂).
        let cross = d0 * d0 * (d1 + d2) + d1 * d1 * (d0 + d2) + d2 * d2 * (d0 + d1);
        self.depth_cubed += area / 10.0 * (d0 * d0 * d0 + d1 * d1 * d1 + d2 * d2 * d2 + cross + d0 * d1 * d2);
    }
}

/// The tool's surface inside B: its area, and `−∫ n dA` over it (B's frame), the way the tool moves to
/// shrink the overlap fastest (on a face, the face's normal).
#[derive(Default)]
struct Surface {
    area: f32,
    way_out: Vec3,
}

impl Surface {
    /// A triangle's part inside B: its outward normal `n` and its area.
    fn add(&mut self, n: Vec3, area: f32) {
        self.area += area;
        self.way_out -= n * area;
    }

    /// Adds another part of the surface inside B.
    fn merge(&mut self, other: &Surface) {
        self.area += other.area;
        self.way_out += other.way_out;
    }

    /// The way out in the world's frame, unless the tool is nearly sunk whole (its surface inside B
    /// almost closed: no way out stands out, and the columns' push is kept).
    fn way_out(&self, pose_b: &Pose) -> Option<Vec3> {
        (self.way_out.length() > Self::OPEN * self.area).then(|| pose_b.transform_vector(self.way_out).normalize())
    }

    /// The least `|∫ n dA|` per unit of area for the way out to count (a ball sunk to 0.9 of its
    /// diameter: 0.1).
    const OPEN: f32 = 0.1;
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
    surface: Surface,
}

impl Group {
    /// Adds the column under one triangle: `g` the direction into B, `cos` its cosine with the
    /// triangle's outward normal, `(Δφ, σ₂)` how the distance bends there ([`curvature_at`]).
    fn add(&mut self, column: Column, g: Vec3, cos: f32, (laplacian, sigma2): (f32, f32)) {
        if column.depth <= 0.0 {
            return;
        }
        // The curvature term: a column's cross-section is 1 − Δφ·s + σ₂·s² of its base's at s out from
        // the tool's surface, so its volume is ∫φ − Δφ/2·∫φ² + σ₂/3·∫φ³ per unit of cos·dA; kept to
        // half the column either way.
        let bend = -0.5 * laplacian * column.depth_squared + sigma2 / 3.0 * column.depth_cubed;
        let bend = bend.clamp(-0.5 * column.depth, 0.5 * column.depth);
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
