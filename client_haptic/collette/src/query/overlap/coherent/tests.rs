use super::super::tests::{ball, brute_force, torus, unit_box};
use super::*;
use crate::query::overlap::overlap_budgeted;
use glam::Quat;

/// The plain exact aggregated query's answer.
fn plain(a: &InnerSphereTree, pa: &Pose, b: &InnerSphereTree, pb: &Pose) -> f32 {
    let mut set = ContactSet::new();
    overlap_budgeted(a, pa, b, pb, Budget::Unlimited, &mut QueryWorkspace::new(), &mut set).total_volume
}

/// Walks `path` with one list and checks every answer against the plain query and its own contacts.
fn walk(list: &mut CoherentOverlap, a: &InnerSphereTree, b: &InnerSphereTree, pb: &Pose, path: &[Pose]) -> usize {
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let mut touching = 0;
    for (k, pa) in path.iter().enumerate() {
        let r = list.query(a, pa, b, pb, &mut ws, &mut set);
        let reference = plain(a, pa, b, pb);
        let tolerance = 1e-5 * reference + 1e-12;
        assert!((r.total_volume - reference).abs() <= tolerance, "step {k}: {} vs {reference}", r.total_volume);
        assert!(r.complete && r.estimated_volume == 0.0 && set.total_volume == r.total_volume);
        assert_eq!(set.len() as u32, r.leaf_pairs + r.aggregated_pairs, "step {k}: one contact per pair or node");
        let carried: f32 = set.as_slice().iter().map(|c| c.volume).sum();
        assert!((carried - r.total_volume).abs() <= tolerance, "step {k}: the contacts carry the volume");
        for c in set.as_slice() {
            assert!((c.normal.length() - 1.0).abs() < 1e-4 && c.volume > 0.0 && c.point.is_finite(), "{c:?}");
        }
        touching += (reference > 0.0) as usize;
    }
    touching
}

/// `n` poses from `from` to `to`, turning by `turn` radians about a tilted axis on the way.
fn path(from: Vec3, to: Vec3, turn: f32, n: usize) -> Vec<Pose> {
    let axis = Vec3::new(0.3, 1.0, 0.2).normalize();
    (0..n)
        .map(|k| {
            let t = k as f32 / (n - 1) as f32;
            Pose::new(from.lerp(to, t), Quat::from_axis_angle(axis, turn * t))
        })
        .collect()
}

#[test]
fn the_coherent_query_is_exact_at_every_step_and_collects_only_after_moving_by_its_skin() {
    // A small dense torus sliding into a box and out through its far side, and the same with the box
    // as object A (then the box's nodes hold the torus's inside its spheres).
    let small = torus(600).scaled(0.15);
    let large = unit_box(300);
    let steps = path(Vec3::new(0.75, 0.1, 0.05), Vec3::new(-0.2, 0.0, 0.1), 1.5, 600);
    let skin = CoherentOverlap::skin_for(&small, &large);
    assert!(skin > 0.0);
    let mut list = CoherentOverlap::new(skin).expect("a valid skin");
    let touching = walk(&mut list, &small, &large, &Pose::IDENTITY, &steps);
    assert!(touching > 400, "the torus meets the box along most of the path ({touching} of 600)");
    let st = list.stats();
    assert_eq!(st.queries, 600);
    assert_eq!(st.overflows, 0);
    // The path is 0.95 long and turns 1.5 rad over the torus's ~0.15 radius: at most about (0.95 + 0.23)
    // / skin collections are needed; the list must not be collected at every step either.
    let needed = ((0.95 + 1.5 * small.root().bound.radius) / skin).ceil() as u64;
    assert!(st.collections >= needed / 2 && st.collections <= needed + 1, "{st:?}, about {needed} needed");
    assert!(st.collections < 300, "{st:?}");

    let mut swapped = CoherentOverlap::new(skin).expect("a valid skin");
    let inverse: Vec<Pose> = steps.iter().map(Pose::inverse).collect();
    walk(&mut swapped, &large, &small, &Pose::IDENTITY, &inverse);
    assert!(swapped.stats().collections < swapped.stats().queries, "{:?}", swapped.stats());
}

#[test]
fn a_node_that_leaves_the_sphere_it_was_inside_is_descended_against_it() {
    // A tiny torus inside a ball's (nearly single) sphere, just under its surface, moving out through
    // it: its nodes are kept as "inside, near the surface" and must be resolved pair by pair once out.
    let ball = ball(50);
    let big = ball.spheres().iter().map(|s| s.radius).fold(0.0, f32::max);
    let tiny = torus(400).scaled(0.06);
    let skin = 0.02;
    let mut list = CoherentOverlap::new(skin).expect("a valid skin");
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let first = Pose::from_translation(Vec3::X * (big - 0.075));
    list.query(&tiny, &first, &ball, &Pose::IDENTITY, &mut ws, &mut set);
    assert!(list.maybe.len > 0, "nodes inside the sphere but within the skin of its surface are kept");
    let steps = path(first.translation, Vec3::X * (big + 0.1), 0.4, 200);
    let touching = walk(&mut list, &tiny, &ball, &Pose::IDENTITY, &steps);
    assert!(touching > 50 && touching < 200, "the torus leaves the ball on the way ({touching} of 200)");
}

#[test]
fn a_jump_a_tree_changed_or_a_list_too_small_is_still_answered_exactly() {
    let small = torus(600).scaled(0.15);
    let large = unit_box(300);
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let near = Pose::new(Vec3::new(0.5, 0.1, 0.0), Quat::from_rotation_z(0.2));
    let far = Pose::new(Vec3::new(0.1, -0.2, 0.1), Quat::from_rotation_x(1.0));
    let mut list = CoherentOverlap::new(0.01).expect("a valid skin");
    for pa in [near, far, near] {
        let r = list.query(&small, &pa, &large, &Pose::IDENTITY, &mut ws, &mut set);
        assert!((r.total_volume - plain(&small, &pa, &large, &Pose::IDENTITY)).abs() <= 1e-5 * r.total_volume);
    }
    assert_eq!(list.stats().collections, 3, "every jump is farther than the skin");
    // Another tree at the same pose: the list is not the one for it.
    let other = torus(300).scaled(0.15);
    let r = list.query(&other, &near, &large, &Pose::IDENTITY, &mut ws, &mut set);
    assert_eq!(list.stats().collections, 4);
    assert!((r.total_volume - plain(&other, &near, &large, &Pose::IDENTITY)).abs() <= 1e-5 * r.total_volume);
    // Room for 8 candidates only: counted as an overflow and answered by the plain query.
    let mut cramped = CoherentOverlap::with_capacity(0.01, 8).expect("a valid skin");
    for _ in 0..2 {
        let r = cramped.query(&small, &near, &large, &Pose::IDENTITY, &mut ws, &mut set);
        let reference = brute_force(&small, &near, &large, &Pose::IDENTITY);
        assert!((r.total_volume as f64 - reference).abs() <= 1e-4 * reference);
    }
    assert_eq!(cramped.stats().overflows, 2);
    // A skin of 0 collects every time and stays exact.
    let mut eager = CoherentOverlap::new(0.0).expect("0 is a valid skin");
    walk(&mut eager, &small, &large, &Pose::IDENTITY, &[near, near, far]);
    assert_eq!(eager.stats().collections, 3);
}

#[test]
fn a_skin_that_is_not_a_length_is_refused_with_its_value() {
    for skin in [-0.001, f32::NAN, f32::INFINITY] {
        let e = CoherentOverlap::new(skin).expect_err("not a length");
        assert!(e.to_string().starts_with(&format!("invalid skin {skin}")), "{e}");
    }
}
