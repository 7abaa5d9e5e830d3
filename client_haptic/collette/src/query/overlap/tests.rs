use super::*;
use crate::shape::{box_buffers, lens_volume, torus_buffers, uv_sphere_buffers};
use crate::{BuildOptions, TriMesh, build};
use glam::Quat;
use std::sync::OnceLock;
use std::time::Instant;

fn tree_with((v, t): (Vec<Vec3>, Vec<[u32; 3]>), options: &BuildOptions) -> InnerSphereTree {
    build(&TriMesh::new(v, t).expect("valid mesh"), options, &mut |_| {}).expect("builds").0
}

fn tree_of(v: Vec<Vec3>, t: Vec<[u32; 3]>, spheres: usize) -> InnerSphereTree {
    tree_with((v, t), &BuildOptions::spheres(spheres))
}

/// A tree whose spheres all lie inside the mesh (`surface_offset` 0): its packing is a lower bound.
fn inner_tree_of(v: Vec<Vec3>, t: Vec<[u32; 3]>, spheres: usize) -> InnerSphereTree {
    tree_with((v, t), &BuildOptions { surface_offset: 0.0, ..BuildOptions::spheres(spheres) })
}

pub(super) fn ball(spheres: usize) -> InnerSphereTree {
    let (v, t) = uv_sphere_buffers(1.0, 32, 64);
    inner_tree_of(v, t, spheres)
}

/// A torus (R 0.7, r 0.3) of 300 spheres: many spheres of many sizes (a ball's packing is nearly one
/// sphere, too simple to exercise a descent).
pub(super) fn torus(spheres: usize) -> InnerSphereTree {
    let (v, t) = torus_buffers(0.7, 0.3, 48, 24);
    tree_of(v, t, spheres)
}

fn small_tree() -> &'static InnerSphereTree {
    static T: OnceLock<InnerSphereTree> = OnceLock::new();
    T.get_or_init(|| torus(300))
}

pub(super) fn unit_box(spheres: usize) -> InnerSphereTree {
    let (v, t) = box_buffers(Vec3::splat(0.5));
    tree_of(v, t, spheres)
}

/// Brute force over all sphere pairs (weighted lens volumes): the reference for the tree traversal.
pub(super) fn brute_force(a: &InnerSphereTree, pa: &Pose, b: &InnerSphereTree, pb: &Pose) -> f64 {
    let mut sum = 0.0;
    for (sa, wa) in a.spheres().iter().zip(a.weights()) {
        let ca = pa.transform_point(sa.center);
        for (sb, wb) in b.spheres().iter().zip(b.weights()) {
            let cb = pb.transform_point(sb.center);
            sum += lens_volume(sa.radius, sb.radius, ca.distance(cb)) as f64 * (wa * wb) as f64;
        }
    }
    sum
}

fn volume(a: &InnerSphereTree, pa: &Pose, b: &InnerSphereTree, pb: &Pose) -> f32 {
    overlap_volume(a, pa, b, pb, &mut QueryWorkspace::new()).total_volume
}

#[test]
fn the_tree_traversal_finds_every_overlapping_pair() {
    let t = small_tree();
    assert!(t.spheres().len() > 200, "a tree worth descending");
    let pb = Pose::new(Vec3::new(0.9, 0.3, -0.2), Quat::from_rotation_y(0.4));
    let exact = brute_force(t, &Pose::IDENTITY, t, &pb);
    let got = volume(t, &Pose::IDENTITY, t, &pb) as f64;
    assert!(exact > 0.0 && (got - exact).abs() < 1e-4 * exact, "tree {got} vs brute force {exact}");
}

#[test]
fn two_ball_trees_match_the_analytic_lens() {
    // Greedy packing of a ball is (nearly) its inscribed ball, so the overlap is the lens of the balls.
    for (n, tolerance) in [(100, 0.02), (2000, 0.02)] {
        let t = ball(n);
        for d in [0.3f32, 0.7, 1.0] {
            let analytic = lens_volume(1.0, 1.0, d) as f64;
            let pose = Pose::from_translation(Vec3::X * d);
            let packed = volume(&t.unweighted(), &Pose::IDENTITY, &t.unweighted(), &pose) as f64;
            let got = volume(&t, &Pose::IDENTITY, &t, &pose) as f64;
            assert!(packed <= analytic * 1.0001, "a packing overlap never exceeds the true overlap");
            let error = (analytic - got) / analytic;
            assert!(error.abs() < tolerance, "n={n} d={d}: relative error {error}");
        }
    }
}

#[test]
fn the_overlap_of_two_boxes_converges_to_the_exact_value_and_the_weights_close_the_gap() {
    // Unit cubes offset by half a side along x and a quarter along y: exact overlap 0.5 * 0.75 = 0.375.
    let exact = 0.375f64;
    let pb = Pose::from_translation(Vec3::new(0.5, 0.25, 0.0));
    let (mut packed_errors, mut weighted_errors) = (Vec::new(), Vec::new());
    for n in [200, 2000, 8000] {
        let (v, t) = box_buffers(Vec3::splat(0.5));
        let t = inner_tree_of(v, t, n);
        let packed = volume(&t.unweighted(), &Pose::IDENTITY, &t.unweighted(), &pb) as f64;
        let got = volume(&t, &Pose::IDENTITY, &t, &pb) as f64;
        assert!(packed <= exact * 1.0001, "the packing's own overlap never exceeds the true one");
        packed_errors.push((exact - packed) / exact);
        weighted_errors.push(((exact - got) / exact).abs());
    }
    assert!(packed_errors.windows(2).all(|w| w[1] < w[0]), "errors {packed_errors:?} shrink");
    assert!(packed_errors[2] > 0.15, "the packing alone is well short: {packed_errors:?}");
    // Measured: 4.3 %, 1.4 %, 0.8 % (the packing alone: 39 %, 26 %, 20 % short).
    assert!(weighted_errors.iter().all(|&e| e < 0.06) && weighted_errors[2] < 0.02, "{weighted_errors:?}");
}

#[test]
fn overlap_is_symmetric_in_its_two_objects() {
    let (a, b) = (small_tree(), unit_box(200));
    let pa = Pose::new(Vec3::new(0.1, 0.2, 0.3), Quat::from_rotation_x(0.3));
    let pb = Pose::new(Vec3::new(0.8, 0.1, 0.2), Quat::from_rotation_z(1.1));
    let mut ws = QueryWorkspace::new();
    let (mut s1, mut s2) = (ContactSet::new(), ContactSet::new());
    let ab = overlap(a, &pa, &b, &pb, &mut ws, &mut s1);
    let ba = overlap(&b, &pb, a, &pa, &mut ws, &mut s2);
    assert!(ab.total_volume > 0.0);
    assert!((ab.total_volume - ba.total_volume).abs() <= 1e-4 * ab.total_volume);
    assert_eq!(ab.leaf_pairs, ba.leaf_pairs);
    let sum_normals = |s: &ContactSet| s.as_slice().iter().map(|c| c.normal * c.volume).sum::<Vec3>();
    assert!((sum_normals(&s1) + sum_normals(&s2)).length() <= 1e-3 * sum_normals(&s1).length().max(1e-9));
}

#[test]
fn a_rigid_motion_of_both_objects_changes_nothing() {
    let t = small_tree();
    let (pa, pb) = (Pose::IDENTITY, Pose::new(Vec3::new(0.7, 0.5, 0.0), Quat::from_rotation_y(0.9)));
    let m = Pose::new(Vec3::new(10.0, -3.0, 2.0), Quat::from_euler(glam::EulerRot::XYZ, 0.4, -1.2, 2.0));
    let before = volume(t, &pa, t, &pb);
    let after = volume(t, &m.mul_pose(&pa), t, &m.mul_pose(&pb));
    assert!((before - after).abs() <= 2e-3 * before, "{before} vs {after}");
}

#[test]
fn small_motions_give_small_volume_changes() {
    let t = small_tree();
    let step = 1e-3;
    let mut last = volume(t, &Pose::IDENTITY, t, &Pose::from_translation(Vec3::X * 1.0));
    for k in 1..200 {
        let v = volume(t, &Pose::IDENTITY, t, &Pose::from_translation(Vec3::X * (1.0 + k as f32 * step)));
        // The derivative of an overlap volume is bounded by the contact area (< 4π r² here).
        assert!((v - last).abs() <= 4.0 * std::f32::consts::PI * step * 1.01, "jump of {} at step {k}", v - last);
        last = v;
    }
}

#[test]
fn the_budgeted_estimate_approaches_the_full_answer() {
    let t = unit_box(2000);
    let pb = Pose::new(Vec3::new(0.3, 0.1, 0.0), Quat::from_rotation_z(0.3));
    let mut ws = QueryWorkspace::new();
    let mut set = ContactSet::new();
    let full = overlap(&t, &Pose::IDENTITY, &t, &pb, &mut ws, &mut set);
    assert!(full.complete && full.estimated_volume == 0.0);
    let mut errors = Vec::new();
    for pairs in [10, 100, 1000, 10_000, 1_000_000] {
        let r = overlap_budgeted(&t, &Pose::IDENTITY, &t, &pb, Budget::NodePairs(pairs), &mut ws, &mut set);
        assert!(r.node_pairs <= pairs + 1, "stopped at {} for a budget of {pairs}", r.node_pairs);
        assert!(set.truncated || r.complete);
        errors.push(((r.total_volume - full.total_volume) / full.total_volume).abs());
    }
    assert!(errors[0] < 1.0, "even the coarsest estimate is within 100 %: {errors:?}");
    assert!(errors[3] < 0.1, "{errors:?}");
    assert!(errors[4] < 1e-4, "an ample budget gives the exact answer: {errors:?}");
}

#[test]
fn a_time_budget_is_held_within_a_small_margin() {
    let t = unit_box(5000);
    let pb = Pose::new(Vec3::new(0.1, 0.05, 0.0), Quat::from_rotation_z(0.3));
    let mut ws = QueryWorkspace::new();
    let mut set = ContactSet::new();
    let budget = std::time::Duration::from_micros(50);
    let mut overshoots = Vec::new();
    for _ in 0..50 {
        let start = Instant::now();
        let r = overlap_budgeted(&t, &Pose::IDENTITY, &t, &pb, Budget::Deadline(start + budget), &mut ws, &mut set);
        overshoots.push(start.elapsed().saturating_sub(budget));
        assert!(!r.complete && r.estimated_volume > 0.0, "{r:?}");
    }
    overshoots.sort();
    // The median run overshoots by at most the final estimation pass (bounded by the ring capacity).
    assert!(overshoots[25] < std::time::Duration::from_micros(150), "median overshoot {:?}", overshoots[25]);
}

/// Checks every query kind against brute force at `pose` and that the contacts carry the volume;
/// returns how many contacts the every-pair and the aggregated query gave.
fn check_every_query(a: &InnerSphereTree, pa: &Pose, b: &InnerSphereTree, pb: &Pose) -> (usize, usize) {
    let reference = brute_force(a, pa, b, pb);
    let mut ws = QueryWorkspace::new();
    let mut set = ContactSet::new();
    let close = |v: f32| (v as f64 - reference).abs() <= 1e-4 * reference + 1e-9;
    let every = overlap(a, pa, b, pb, &mut ws, &mut set);
    assert!(close(every.total_volume), "every-pair {} vs brute force {reference}", every.total_volume);
    assert_eq!(set.len() as u32, every.leaf_pairs, "one contact per overlapping sphere pair");
    let carried: f64 = set.as_slice().iter().map(|c| c.volume as f64).sum();
    assert!((carried - every.total_volume as f64).abs() <= 1e-4 * reference + 1e-9, "contacts carry the volume");
    let aggregated = overlap_budgeted(a, pa, b, pb, Budget::Unlimited, &mut ws, &mut set);
    assert!(close(aggregated.total_volume), "aggregated {} vs brute force {reference}", aggregated.total_volume);
    assert!(aggregated.complete && aggregated.estimated_volume == 0.0);
    let carried: f64 = set.as_slice().iter().map(|c| c.volume as f64).sum();
    assert!((carried - aggregated.total_volume as f64).abs() <= 1e-4 * reference + 1e-9, "contacts carry the volume");
    assert_eq!(set.len() as u32, aggregated.leaf_pairs + aggregated.aggregated_pairs);
    for c in set.as_slice() {
        assert!((c.normal.length() - 1.0).abs() < 1e-4 && c.volume > 0.0 && c.point.is_finite(), "{c:?}");
    }
    let contacts = (every.leaf_pairs as usize, set.len());
    assert!(close(overlap_volume(a, pa, b, pb, &mut ws).total_volume));
    let ample = overlap_budgeted(a, pa, b, pb, Budget::NodePairs(u32::MAX), &mut ws, &mut set);
    assert!(close(ample.total_volume), "budgeted with an ample budget {}", ample.total_volume);
    contacts
}

#[test]
fn every_query_matches_brute_force_for_trees_of_different_scales() {
    // A small dense torus against a larger box: deep in the descent a subtree of one meets a single
    // sphere of the other (the exact query's shortcut), and whole subtrees lie inside single spheres.
    let small = torus(600).scaled(0.15);
    assert!(small.spheres().len() >= 500);
    let large = unit_box(300);
    for (k, offset) in [Vec3::new(0.42, 0.1, 0.05), Vec3::new(0.3, 0.3, 0.3), Vec3::ZERO, Vec3::new(0.55, 0.0, 0.2)]
        .into_iter()
        .enumerate()
    {
        let pa = Pose::new(offset, Quat::from_rotation_y(0.3 * k as f32));
        let pb = Pose::new(Vec3::new(0.02, -0.01, 0.0), Quat::from_rotation_x(0.2));
        let small_first = check_every_query(&small, &pa, &large, &pb);
        let large_first = check_every_query(&large, &pb, &small, &pa);
        if offset == Vec3::ZERO {
            // The torus lies deep inside the box: whichever tree is A, most of its nodes lie inside
            // single spheres of the box and give one contact each.
            for (every, aggregated) in [small_first, large_first] {
                assert!(aggregated * 3 < every, "{aggregated} aggregated contacts against {every} pairs");
            }
        }
    }
}

#[test]
fn leaves_of_several_spheres_give_the_same_answer() {
    // Trees from other builders may hold several spheres per leaf: every path must handle them.
    let one = unit_box(400);
    let several = InnerSphereTree::from_spheres_in_leaves(one.spheres().to_vec(), one.mesh_volume(), 3);
    several.validate().expect("a valid tree");
    let counts: Vec<u32> = several.nodes().iter().filter(|n| n.leaf).map(|n| n.count).collect();
    assert!(counts.iter().any(|&c| c > 1), "{} spheres, leaf sizes {counts:?}", several.spheres().len());
    let small = InnerSphereTree::from_spheres_in_leaves(unit_box(300).scaled(0.2).spheres().to_vec(), 0.008, 4);
    for offset in [Vec3::new(0.45, 0.2, 0.0), Vec3::new(0.2, 0.1, 0.0), Vec3::new(0.6, 0.0, 0.3)] {
        let pb = Pose::new(offset, Quat::from_rotation_z(0.7));
        check_every_query(&several, &Pose::IDENTITY, &several, &pb);
        check_every_query(&several, &Pose::IDENTITY, &one, &pb);
        check_every_query(&one, &Pose::IDENTITY, &several, &pb);
        check_every_query(&small, &pb, &several, &Pose::IDENTITY);
        check_every_query(&several, &Pose::IDENTITY, &small, &pb);
    }
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    fn pose() -> impl Strategy<Value = Pose> {
        (-1.5f32..1.5, -1.5f32..1.5, -1.5f32..1.5, -3.2f32..3.2, -3.2f32..3.2, -3.2f32..3.2).prop_map(
            |(x, y, z, a, b, c)| Pose::new(Vec3::new(x, y, z), Quat::from_euler(glam::EulerRot::XYZ, a, b, c)),
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn random_poses_match_brute_force_and_are_symmetric(pa in pose(), pb in pose()) {
            let t = small_tree();
            let reference = brute_force(t, &pa, t, &pb);
            let ab = volume(t, &pa, t, &pb) as f64;
            let ba = volume(t, &pb, t, &pa) as f64;
            prop_assert!((ab - reference).abs() <= 1e-3 * reference + 1e-6);
            prop_assert!((ab - ba).abs() <= 1e-3 * ab + 1e-6);
            prop_assert!(ab <= t.mesh_share() as f64 * 1.001);
        }

        #[test]
        fn random_poses_of_unequal_trees_agree_in_every_query(pa in pose(), pb in pose()) {
            static SMALL: OnceLock<InnerSphereTree> = OnceLock::new();
            let small = SMALL.get_or_init(|| unit_box(400).scaled(0.3));
            check_every_query(small, &pa, small_tree(), &pb);
        }
    }
}

#[test]
fn spheres_reaching_past_the_surface_count_a_shallow_touch_and_keep_a_deep_one_exact() {
    // A 0.8 × 0.8 × 0.2 slab pressed flat into the top of a unit cube: exact overlap 0.64 × depth.
    let ratios = |offset: f32| -> Vec<f64> {
        let options = BuildOptions { surface_offset: offset, ..BuildOptions::spheres(2000) };
        let tree = |half: Vec3| tree_with(box_buffers(half), &options);
        let (slab, block) = (tree(Vec3::new(0.4, 0.4, 0.1)), tree(Vec3::splat(0.5)));
        [0.005f32, 0.01, 0.02, 0.1, 0.2]
            .iter()
            .map(|&depth| {
                let pose = Pose::new(Vec3::new(0.03, 0.01, 0.6 - depth), Quat::from_rotation_z(0.3));
                volume(&slab, &pose, &block, &Pose::IDENTITY) as f64 / (0.64 * depth as f64)
            })
            .collect()
    };
    let (inside, reaching) = (ratios(0.0), ratios(BuildOptions::DEFAULT_SURFACE_OFFSET));
    // Measured: inside 0.07, 0.27, 0.78, 1.04, 1.01; reaching 0.45, 0.66, 1.01, 1.03, 1.00 (the voxel
    // is 11 mm here: the shallow presses are half a voxel to two voxels deep).
    for k in 0..3 {
        assert!(reaching[k] > inside[k] + 0.15, "depth #{k}: {} against {} inside", reaching[k], inside[k]);
    }
    for r in inside[3..].iter().chain(&reaching[3..]) {
        assert!((r - 1.0).abs() < 0.05, "a deep press is counted whole: {inside:?} / {reaching:?}");
    }
}
