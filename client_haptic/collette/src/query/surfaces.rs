//! Overlap of two objects that each have a surface shell and a signed distance grid: the overlap's
//! boundary itself, both parts of it.
//!
//! You need this module when the force must be right however deep the objects overlap: where a tool
//! reaches past the middle of a thin part of the object (a bunny's ear through a ring), the columns of
//! [`overlap_shell`](crate::overlap_shell) run to the nearer face, the wrong one, while the boundary does
//! not care. The overlap of A and B is bounded by A's surface inside B and B's surface inside A;
//! the divergence theorem over that closed boundary gives its volume (`V = ⅓∮ y·n dA`), its centroid
//! (`∫y_k dV = ½∮ y_k² n_k dA`) and the way out that shrinks it fastest (`−∫ n_A dA` over A's part,
//! which equals `∫ n_B dA` over B's part), each from the two shells clipped by the other's distance
//! (linear over each triangle, bent through its edges' middles as in `overlap_shell`). It reports one
//! contact: the whole overlap, at its centroid, along that way out. An overlap only a few of A's grid
//! voxels deep is taken from A's columns instead (`overlap_shell`), which are exact on a face at any
//! depth where A's grid cannot draw B's part (blended smoothly from two voxels deep to six).

use crate::query::QueryWorkspace;
use crate::query::overlap::{Budget, OverlapResult};
use crate::query::shell::{inside_pieces, leaf_triangles, outside};
use crate::shape::{SignedDistanceGrid, SurfaceShell};
use glam::{DVec3, Vec3};
use haptic_common::{Contact, ContactSet, Pose};

/// Overlap of object A (its `a_shell` and `a_grid`, at `pose_a`) and object B (its `b_shell` and
/// `b_grid`, at `pose_b`): the volume and one world-frame contact — at the overlap's centroid, its
/// normal the direction that moves A out of B fastest, its volume the overlap's.
///
/// In the result `leaf_pairs` counts the triangles of both shells inside the other object and
/// `node_pairs` the shells' nodes visited.
#[allow(clippy::too_many_arguments)]
pub fn overlap_surfaces(
    a_shell: &SurfaceShell,
    a_grid: &SignedDistanceGrid,
    pose_a: &Pose,
    b_shell: &SurfaceShell,
    b_grid: &SignedDistanceGrid,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
    out: &mut ContactSet,
) -> OverlapResult {
    overlap_surfaces_budgeted(a_shell, a_grid, pose_a, b_shell, b_grid, pose_b, Budget::Unlimited, ws, out)
}

/// [`overlap_surfaces`] that stops when `budget` runs out. A's columns
/// ([`overlap_shell`](crate::overlap_shell)) come first, then the boundary; cut short in the boundary,
/// it answers with the columns' contacts (their push the way out, exact on faces at any depth), cut
/// short in the columns, with the part of them it measured. Either way `complete` is false.
#[allow(clippy::too_many_arguments)]
pub fn overlap_surfaces_budgeted(
    a_shell: &SurfaceShell,
    a_grid: &SignedDistanceGrid,
    pose_a: &Pose,
    b_shell: &SurfaceShell,
    b_grid: &SignedDistanceGrid,
    pose_b: &Pose,
    budget: Budget,
    ws: &mut QueryWorkspace,
    out: &mut ContactSet,
) -> OverlapResult {
    let columns = super::shell::overlap_shell_budgeted(a_shell, pose_a, b_grid, pose_b, budget, ws, out);
    if !columns.complete || columns.total_volume <= 0.0 {
        return columns;
    }
    let (mut force, mut moment, mut listed, mut deepest) = (Vec3::ZERO, Vec3::ZERO, 0.0f32, 0.0f32);
    for c in out.as_slice() {
        force += c.normal * c.volume;
        moment += c.point * c.volume;
        listed += c.volume;
        deepest = deepest.max(c.depth);
    }
    let mut result = OverlapResult { complete: true, node_pairs: columns.node_pairs, ..OverlapResult::default() };
    // Sums in the world frame, about a point near the overlap (A's centre) to keep them small.
    let origin = pose_a.transform_point(a_shell.bound().0);
    let mut sums = Boundary::default();
    let mut until_clock = 0;
    let mut pass = |shell, pose, grid, grid_pose, side, sums: &mut Boundary, result: &mut OverlapResult| {
        boundary(shell, pose, grid, grid_pose, origin, side, (budget, &mut until_clock), ws, sums, result)
    };
    if !pass(a_shell, pose_a, b_grid, pose_b, Side::A, &mut sums, &mut result)
        || !pass(b_shell, pose_b, a_grid, pose_a, Side::B, &mut sums, &mut result)
    {
        // `out` still holds the columns' contacts.
        return OverlapResult { complete: false, node_pairs: result.node_pairs, ..columns };
    }
    // The two parts, each clipped by the other's interpolated distance, meet along nearly the same curve:
    // what the boundary misses there counts in proportion to its distance from the origin, so the sums
    // move to the middle of A's part (beside that curve for a shallow overlap, whose small volume is the
    // difference of two large integrals about a far origin). For a closed boundary moving the origin by
    // δ changes nothing; for this one it takes δ·∮n dA / 3 off the volume and adjusts the moment.
    let closure = sums.a_area + sums.b_area;
    let delta = if sums.a_total > 0.0 { sums.a_moment / sums.a_total } else { DVec3::ZERO };
    // ∮ y·n dA is the sum of the per-axis ∮ y_k n_k dA.
    let volume = (sums.first.element_sum() - delta.dot(closure)) / 3.0;
    let boundary_moment = sums.moment * 0.5 - delta * sums.first + delta * delta * closure * 0.5;
    // The two parts' ways out agree on a closed boundary; their mean halves what either misses.
    let out_of_b = (sums.b_area - sums.a_area) * 0.5;
    let mut closed = None;
    if volume > 0.0
        && let Some(normal) = out_of_b.as_vec3().try_normalize()
    {
        closed = Some((volume as f32, origin + (delta + boundary_moment / volume).as_vec3(), normal));
    }
    // B's part is clipped by A's grid, which cannot draw an overlap thinner than a few of its voxels (a
    // box's corner 0.1 mm in); A's columns are exact there on any face. So: the columns up to two of A's
    // voxels deep, the boundary from six, blended smoothly between. A's deepest point inside B is the
    // one the columns report.
    let voxel = a_grid.voxel_size();
    let t = ((deepest - 2.0 * voxel) / (4.0 * voxel)).clamp(0.0, 1.0);
    let w = t * t * (3.0 - 2.0 * t);
    let column =
        (listed > 0.0).then(|| force.try_normalize().map(|n| (columns.total_volume, moment / listed, n))).flatten();
    let blended = match (column, closed) {
        (Some(c), Some(b)) => {
            Some((c.0 + (b.0 - c.0) * w, c.1 + (b.1 - c.1) * w, (c.2 + (b.2 - c.2) * w).normalize_or(b.2)))
        }
        (None, Some(b)) => Some((b.0 * w, b.1, b.2)),
        (Some(c), None) => Some((c.0 * (1.0 - w), c.1, c.2)),
        (None, None) => None,
    };
    out.clear();
    if let Some((volume, point, normal)) = blended.filter(|b| b.0 > 0.0) {
        out.push(Contact { point, normal, volume, depth: deepest });
        result.total_volume = volume;
    }
    out.total_volume = result.total_volume;
    result
}

/// Which object's surface a part of the boundary is.
#[derive(Clone, Copy, PartialEq)]
enum Side {
    A,
    B,
}

/// The boundary's integrals so far (world frame, about the origin), in f64: the pieces' terms cancel
/// between the two parts.
#[derive(Default)]
struct Boundary {
    /// ∮ y_k² n_k dA and ∮ y_k n_k dA, per axis.
    moment: DVec3,
    first: DVec3,
    /// ∫ y dA and ∫ dA over A's part.
    a_moment: DVec3,
    a_total: f64,
    /// ∫ n dA over A's part and over B's part.
    a_area: DVec3,
    b_area: DVec3,
}

/// Adds the part of `shell` (at `pose`) inside the object of `grid` (at `grid_pose`) to `sums`.
#[allow(clippy::too_many_arguments)]
fn boundary(
    shell: &SurfaceShell,
    pose: &Pose,
    grid: &SignedDistanceGrid,
    grid_pose: &Pose,
    origin: Vec3,
    side: Side,
    (budget, until_clock): (Budget, &mut u32),
    ws: &mut QueryWorkspace,
    sums: &mut Boundary,
    result: &mut OverlapResult,
) -> bool {
    let into_grid = grid_pose.relative_to(pose);
    let nodes = shell.nodes();
    let stack = &mut ws.nodes;
    stack.clear();
    stack.push(0);
    while let Some(n) = stack.pop() {
        if budget.spent(result.node_pairs, until_clock) {
            return false;
        }
        result.node_pairs += 1;
        let node = nodes[n as usize];
        let center = into_grid.transform_point(node.center);
        if outside(grid, center, node.radius, grid.distance(center)) {
            continue;
        }
        if node.count == 0 {
            stack.push(node.first);
            stack.push(node.first + 1);
            continue;
        }
        for (p, phi, gradients) in leaf_triangles(shell, &node, &into_grid, grid) {
            // The triangle's outward normal, world frame.
            let Some(normal) = grid_pose.transform_vector((p[1] - p[0]).cross(p[2] - p[0])).try_normalize() else {
                continue;
            };
            let normal = normal.as_dvec3();
            let inside = inside_pieces(p, phi, gradients, |piece| {
                let y = piece.map(|(x, _)| (grid_pose.transform_point(x) - origin).as_dvec3());
                let area = 0.5 * (y[1] - y[0]).cross(y[2] - y[0]).length();
                let sum = y[0] + y[1] + y[2];
                // ∫y_k² dA = A/12·(Σ y_ik² + (Σ y_ik)²).
                let squares = y[0] * y[0] + y[1] * y[1] + y[2] * y[2] + sum * sum;
                sums.moment += normal * squares * (area / 12.0);
                sums.first += normal * sum * (area / 3.0);
                match side {
                    Side::A => {
                        sums.a_area += normal * area;
                        sums.a_moment += sum * (area / 3.0);
                        sums.a_total += area;
                    }
                    Side::B => sums.b_area += normal * area,
                }
            });
            if inside {
                result.leaf_pairs += 1;
            }
        }
    }
    true
}
