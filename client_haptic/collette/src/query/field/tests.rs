use super::*;
use crate::Budget;
use crate::shape::{Sphere, TriMesh, box_buffers, torus_buffers, uv_sphere_buffers};
use crate::{BuildOptions, build};
use glam::Quat;
use std::f32::consts::PI;

/// A touched object: its tree and its distance grid.
fn solid(
    (v, t): (Vec<Vec3>, Vec<[u32; 3]>),
    spheres: usize,
    resolution: usize,
) -> (InnerSphereTree, SignedDistanceGrid) {
    let mesh = TriMesh::new(v, t).expect("valid");
    let tree = build(&mesh, &BuildOptions::spheres(spheres), &mut |_| {}).expect("tree").0;
    (tree, SignedDistanceGrid::new(&mesh, resolution).expect("grid"))
}

fn tree_of((v, t): (Vec<Vec3>, Vec<[u32; 3]>), spheres: usize) -> InnerSphereTree {
    build(&TriMesh::new(v, t).expect("valid"), &BuildOptions::spheres(spheres), &mut |_| {}).expect("tree").0
}

/// The volume summed sphere by sphere, without the nodes' shortcuts.
fn sphere_by_sphere(
    a: &InnerSphereTree,
    pose_a: &Pose,
    b: (&InnerSphereTree, &SignedDistanceGrid),
    pose_b: &Pose,
) -> f64 {
    let a_in_b = pose_b.relative_to(pose_a);
    let mut stack = Vec::new();
    a.spheres()
        .iter()
        .zip(a.weights())
        .filter_map(|(s, w)| {
            Part::of(b, a_in_b.transform_point(s.center), s.radius, &mut stack).map(|p| (p.volume * w) as f64)
        })
        .sum()
}

fn cap(r: f32, h: f32) -> f32 {
    let h = h.clamp(0.0, 2.0 * r);
    PI * h * h * (3.0 * r - h) / 3.0
}

#[test]
fn a_sphere_sliding_through_a_flat_face_counts_exactly_its_cap() {
    let (slab, grid) = solid(box_buffers(Vec3::new(1.0, 1.0, 0.5)), 500, 40);
    let r = 0.2;
    let tree = InnerSphereTree::from_spheres(vec![Sphere::new(Vec3::ZERO, r)], sphere_volume(r));
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    for i in 0..=100 {
        // The ball's centre from 0.3 above the top face (z = 0.5) to 0.3 below it.
        let z = 0.8 - 0.006 * i as f32;
        let pose = Pose::new(Vec3::new(0.1, -0.05, z), Quat::from_rotation_x(0.3));
        let got = overlap_field(&tree, &pose, &slab, &grid, &Pose::IDENTITY, &mut ws, &mut set);
        let want = cap(r, r - (z - 0.5));
        assert!((got.total_volume - want).abs() <= 1e-4 * sphere_volume(r), "z {z}: {} vs {want}", got.total_volume);
        if want > 0.0 {
            let contact = set.as_slice()[0];
            assert!((contact.normal - Vec3::Z).length() < 1e-3, "pushed out through the face: {}", contact.normal);
            assert!((contact.volume - got.total_volume).abs() < 1e-7);
            assert!(
                contact.point.z <= 0.5 + 1e-4 && contact.point.z >= z - r - 1e-4,
                "inside the box: {}",
                contact.point
            );
        } else {
            assert!(set.is_empty());
        }
    }
}

#[test]
fn a_box_sunk_in_a_slab_and_a_torus_around_a_ball_give_their_true_volumes_within_a_percent() {
    // A box's slice below a face: its cross-section times the depth.
    let block = tree_of(box_buffers(Vec3::new(0.5, 0.4, 0.3)), 2000);
    let (slab, slab_grid) = solid(box_buffers(Vec3::new(3.0, 3.0, 1.0)), 500, 60);
    let mut ws = QueryWorkspace::new();
    for depth in [0.1f32, 0.2, 0.3, 0.45] {
        let pose = Pose::new(Vec3::new(0.2, 0.1, 1.0 + 0.3 - depth), Quat::from_rotation_z(0.4));
        let got = overlap_field_volume(&block, &pose, &slab, &slab_grid, &Pose::IDENTITY, &mut ws).total_volume;
        let want = 1.0 * 0.8 * depth;
        assert!((got / want - 1.0).abs() < 0.01, "depth {depth}: {got} vs {want}");
    }
    // A curved surface: a torus tube (r 0.3) around a ball of radius 2, its axis on the ball's surface.
    let torus = tree_of(torus_buffers(2.0, 0.3, 96, 48), 3000);
    let (ball, ball_grid) = solid(uv_sphere_buffers(2.0, 64, 128), 500, 80);
    let got = overlap_field_volume(&torus, &Pose::IDENTITY, &ball, &ball_grid, &Pose::IDENTITY, &mut ws).total_volume;
    // The tube's cross-section inside the ball, swept about the axis (Pappus), integrated on a fine grid.
    let n = 600;
    let cell = 0.6 / n as f64;
    let mut exact = 0.0;
    for i in 0..n {
        for k in 0..n {
            let (x, z) = (1.7 + (i as f64 + 0.5) * cell, -0.3 + (k as f64 + 0.5) * cell);
            if (x - 2.0).powi(2) + z * z < 0.09 && x * x + z * z < 4.0 {
                exact += 2.0 * std::f64::consts::PI * x * cell * cell;
            }
        }
    }
    let want = (exact * torus.mesh_share() as f64 / (2.0 * std::f64::consts::PI.powi(2) * 2.0 * 0.09)) as f32;
    assert!((got / want - 1.0).abs() < 0.01, "torus around the ball: {got} vs {want}");
}

#[test]
fn nodes_counted_whole_or_skipped_give_what_their_spheres_would() {
    let torus = tree_of(torus_buffers(0.3, 0.1, 64, 32), 1500);
    let ball = solid(uv_sphere_buffers(0.25, 32, 64), 500, 48);
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let mut aggregated = 0;
    for i in 0..120 {
        let t = i as f32 / 120.0;
        let pose = Pose::new(Vec3::new(-0.6 + 1.2 * t, 0.05 * t, 0.02), Quat::from_rotation_z(3.0 * t));
        let got = overlap_field(&torus, &pose, &ball.0, &ball.1, &Pose::IDENTITY, &mut ws, &mut set);
        let want = sphere_by_sphere(&torus, &pose, (&ball.0, &ball.1), &Pose::IDENTITY);
        assert!(
            (got.total_volume as f64 - want).abs() <= 1e-5 * want.max(1e-6),
            "step {i}: {} vs {want}",
            got.total_volume
        );
        let summed: f32 = set.as_slice().iter().map(|c| c.volume).sum();
        assert!((summed - got.total_volume).abs() <= 1e-5 * got.total_volume.max(1e-9), "contacts carry the volume");
        aggregated += got.aggregated_pairs;
    }
    assert!(aggregated > 0, "some nodes were counted whole");
}

#[test]
fn the_volume_changes_smoothly_along_a_sweep() {
    let torus = tree_of(torus_buffers(0.3, 0.1, 64, 32), 1500);
    let (ball, ball_grid) = solid(uv_sphere_buffers(0.25, 32, 64), 500, 48);
    let mut ws = QueryWorkspace::new();
    let volumes: Vec<f32> = (0..=2000)
        .map(|i| {
            let pose = Pose::new(Vec3::new(-0.6 + 0.0006 * i as f32, 0.03, 0.01), Quat::from_rotation_y(0.2));
            overlap_field_volume(&torus, &pose, &ball, &ball_grid, &Pose::IDENTITY, &mut ws).total_volume
        })
        .collect();
    // A step of 0.6 mm can change the volume by at most the tool's whole cross-section times the step
    // (times √3, the interpolated distance's steepest slope): a node counted whole too early or too
    // late would jump by its whole volume.
    let cross_section: f32 =
        torus.spheres().iter().zip(torus.weights()).map(|(s, w)| PI * s.radius * s.radius * w).sum();
    let bound = cross_section * 0.0006 * 3f32.sqrt();
    let worst = volumes.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0f32, f32::max);
    assert!(volumes.iter().any(|&v| v > 0.0), "the sweep overlaps");
    assert!(worst <= bound, "largest step {worst} over the bound {bound}");
}

#[test]
fn the_penalty_force_changes_smoothly_along_a_sweep_and_jumps_no_more_than_the_two_tree_querys() {
    // The volumetric penalty force is along Σ volume × normal. Its normals must not jump where the
    // interpolant's slope does (the cells' faces). Where a node starts counting whole near the ball's
    // centre (its leaves' normals point every way, the node's one way) the force steps, as it does in
    // the aggregated query of two trees; not by more.
    let torus = tree_of(torus_buffers(0.3, 0.1, 64, 32), 1500);
    let (ball, ball_grid) = solid(uv_sphere_buffers(0.25, 32, 64), 500, 24);
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let mut sweep = |field: bool| -> (f32, f32, f32) {
        let forces: Vec<Vec3> = (0..=2000)
            .map(|i| {
                let pose = Pose::new(Vec3::new(-0.6 + 0.0006 * i as f32, 0.03, 0.01), Quat::from_rotation_y(0.2));
                if field {
                    overlap_field(&torus, &pose, &ball, &ball_grid, &Pose::IDENTITY, &mut ws, &mut set);
                } else {
                    crate::overlap_budgeted(
                        &torus,
                        &pose,
                        &ball,
                        &Pose::IDENTITY,
                        crate::Budget::Unlimited,
                        &mut ws,
                        &mut set,
                    );
                }
                set.as_slice().iter().map(|c| c.normal * c.volume).sum()
            })
            .collect();
        let largest = forces.iter().map(|f| f.length()).fold(0.0f32, f32::max);
        let mut steps: Vec<f32> = forces.windows(2).map(|w| (w[1] - w[0]).length()).collect();
        steps.sort_by(f32::total_cmp);
        (largest, steps[steps.len() * 99 / 100], steps[steps.len() - 1])
    };
    let (largest, p99, worst) = sweep(true);
    let (two_largest, _, two_worst) = sweep(false);
    assert!(largest > 0.0 && p99 <= 0.01 * largest, "99 % of the steps under 1 % of the force: {p99} of {largest}");
    assert!(
        worst / largest <= 1.5 * two_worst / two_largest,
        "largest step {worst} of {largest}; two trees: {two_worst} of {two_largest}"
    );
}

#[test]
fn a_budget_stops_the_descent_and_estimates_the_rest_from_the_nodes_bounds() {
    let torus = tree_of(torus_buffers(0.3, 0.1, 64, 32), 1500);
    let ball = solid(uv_sphere_buffers(0.25, 32, 64), 500, 48);
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let pose = Pose::new(Vec3::new(-0.2, 0.03, 0.01), Quat::from_rotation_y(0.2));
    let exact = overlap_field(&torus, &pose, &ball.0, &ball.1, &Pose::IDENTITY, &mut ws, &mut set);
    assert!(exact.complete && exact.estimated_volume == 0.0 && exact.total_volume > 0.0);
    let ample = overlap_field_budgeted(
        &torus,
        &pose,
        &ball.0,
        &ball.1,
        &Pose::IDENTITY,
        Budget::NodePairs(u32::MAX),
        &mut ws,
        &mut set,
    );
    // A budget never reached changes nothing but the order of the sum (breadth-first).
    let same_volume = (ample.total_volume / exact.total_volume - 1.0).abs() < 1e-5;
    assert_eq!(OverlapResult { total_volume: exact.total_volume, ..ample }, exact, "a budget never reached");
    assert!(same_volume, "{} against {}", ample.total_volume, exact.total_volume);
    let mut errors = Vec::new();
    for nodes in [1, 10, 100, 400] {
        let cut = overlap_field_budgeted(
            &torus,
            &pose,
            &ball.0,
            &ball.1,
            &Pose::IDENTITY,
            Budget::NodePairs(nodes),
            &mut ws,
            &mut set,
        );
        assert!(!cut.complete && set.truncated && cut.estimated_volume > 0.0, "{nodes} nodes: {cut:?}");
        assert_eq!(cut.node_pairs, nodes);
        let summed: f32 = set.as_slice().iter().map(|c| c.volume).sum();
        assert!((summed - cut.total_volume).abs() <= 1e-5 * cut.total_volume, "the estimate is reported as contacts");
        errors.push((cut.total_volume / exact.total_volume - 1.0).abs());
    }
    // Breadth-first, so a cut leaves the tree evenly refined: within 5 % from ten nodes on (of 583).
    assert!(errors[1..].iter().all(|&e| e < 0.05) && errors[3] < 0.01, "{errors:?}");
    let late = overlap_field_budgeted(
        &torus,
        &pose,
        &ball.0,
        &ball.1,
        &Pose::IDENTITY,
        Budget::Deadline(std::time::Instant::now()),
        &mut ws,
        &mut set,
    );
    assert!(!late.complete && late.node_pairs <= Budget::CLOCK_STRIDE && late.total_volume > 0.0, "{late:?}");
}
