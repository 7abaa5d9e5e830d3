//! Steady-state queries and collision steps allocate nothing (the allocator aborts if they do).

use assert_no_alloc::{AllocDisabler, assert_no_alloc};
use collette::pipeline::{
    CollisionConfig, CollisionWorld, Command, NearSpheres, ObjectId, ObjectPose, PairSummary, PoseTrack, SceneContacts,
    TimedPose, WatcherId, WatcherOutput,
};
use collette::shape::box_buffers;
use collette::{
    Budget, BuildOptions, CoherentOverlap, ContactSet, Pose, QueryWorkspace, SignedDistanceGrid, TriMesh, build,
    overlap, overlap_budgeted, overlap_field, overlap_field_budgeted, overlap_field_volume, overlap_volume, probe,
    separation,
};
use glam::{Quat, Vec3};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[global_allocator]
static ALLOCATOR: AllocDisabler = AllocDisabler;

#[test]
fn queries_and_collision_steps_do_not_allocate_once_warmed_up() {
    let (v, t) = box_buffers(Vec3::splat(0.5));
    let mesh = TriMesh::new(v, t).expect("valid");
    let tree = build(&mesh, &BuildOptions::spheres(500), &mut |_| {}).expect("builds").0;
    let grid = SignedDistanceGrid::new(&mesh, 32).expect("grid");
    let mut ws = QueryWorkspace::new();
    let mut set = ContactSet::new();
    let (pa, pb) = (Pose::IDENTITY, Pose::new(Vec3::new(0.4, 0.2, 0.1), Quat::from_rotation_z(0.5)));
    // Collected at the first pose, reused at the second, collected again at the third (moved by 0.05).
    let mut list = CoherentOverlap::new(0.02).expect("a valid skin");
    let moved = [pb, Pose::new(pb.translation + Vec3::X * 0.005, pb.rotation), Pose::from_translation(Vec3::X * 0.45)];
    let run = |ws: &mut QueryWorkspace, set: &mut ContactSet| {
        overlap(&tree, &pa, &tree, &pb, ws, set);
        overlap_budgeted(&tree, &pa, &tree, &pb, Budget::NodePairs(100), ws, set);
        overlap_budgeted(&tree, &pa, &tree, &pb, Budget::Deadline(Instant::now() + Duration::from_micros(30)), ws, set);
        overlap_volume(&tree, &pa, &tree, &pb, ws);
        assert!(overlap_field(&tree, &pa, &tree, &grid, &pb, ws, set).total_volume > 0.0);
        overlap_field_budgeted(&tree, &pa, &tree, &grid, &pb, Budget::NodePairs(20), ws, set);
        overlap_field_volume(&tree, &pa, &tree, &grid, &pb, ws);
        probe(&tree, &pb, Vec3::new(0.3, 0.1, 0.0), 0.05, ws, Some(set));
        separation(&tree, &pa, &tree, &Pose::from_translation(Vec3::X * 3.0), ws);
    };
    run(&mut ws, &mut set);
    assert_no_alloc(|| run(&mut ws, &mut set));
    let mut coherent = |ws: &mut QueryWorkspace, set: &mut ContactSet| {
        for pose in &moved {
            assert!(list.query(&tree, &pa, &tree, pose, ws, set).total_volume > 0.0);
        }
    };
    coherent(&mut ws, &mut set);
    assert_no_alloc(|| coherent(&mut ws, &mut set));
    assert_eq!(list.stats().collections, 4, "collected at the first and third pose of each round");

    let config = CollisionConfig::default();
    let mut world = CollisionWorld::new(&config);
    let shared = Arc::new(tree.clone());
    let (mut tool_in, tool_out) = triple_buffer::triple_buffer(&ObjectPose::default());
    let (mut target_in, target_out) = triple_buffer::triple_buffer(&ObjectPose::default());
    let (contacts_in, mut contacts_out) = triple_buffer::triple_buffer(&ContactSet::new());
    let mut retired = Vec::new();
    world.apply(Command::AddObject(ObjectId(0), shared.clone(), tool_out), &mut |r| retired.push(r));
    world.apply(Command::AddObject(ObjectId(1), shared, target_out), &mut |r| retired.push(r));
    world.apply(
        Command::AddWatcher(WatcherId(0), ObjectId(0), ObjectId(1), WatcherOutput::Contacts(Box::new(contacts_in))),
        &mut |r| retired.push(r),
    );
    // The same pair through a scene watcher, a scene near watcher and a summary watcher.
    let (scene_in, mut scene_out) = triple_buffer::triple_buffer(&SceneContacts::default());
    let (near_in, mut near_out) = triple_buffer::triple_buffer(&NearSpheres::default());
    let (summary_in, mut summary_out) = triple_buffer::triple_buffer(&PairSummary::default());
    let outputs = [
        WatcherOutput::SceneContacts(Box::new(scene_in)),
        WatcherOutput::SceneNear(Box::new(near_in)),
        WatcherOutput::Summary(Box::new(summary_in)),
    ];
    for (i, out) in outputs.into_iter().enumerate() {
        world.apply(Command::AddWatcher(WatcherId(1 + i as u32), ObjectId(0), ObjectId(1), out), &mut |r| {
            retired.push(r)
        });
    }
    tool_in.write(TimedPose { pose: pb, timestamp_us: 5, reach: 0.05 }.into());
    world.step(10, None);
    assert_no_alloc(|| {
        world.step(11, None);
        world.step(12, Some(Instant::now() + Duration::from_micros(100)));
    });
    let latest = contacts_out.read();
    assert!(latest.total_volume > 0.0 && latest.sequence == 3 && latest.timestamp_us == 0);
    // (each with its own share of the last step's time budget)
    assert!(scene_out.read().total_volume() > 0.0 && summary_out.read().total_volume > 0.0);
    assert!(!near_out.read().is_empty());
    // The target measured against its surface grid.
    world.apply(Command::SetSurface(ObjectId(1), Some(Arc::new(grid.clone()))), &mut |r| retired.push(r));
    assert_no_alloc(|| {
        world.step(13, None);
        world.step(14, Some(Instant::now() + Duration::from_micros(100)));
    });
    assert!(contacts_out.read().total_volume > 0.0 && contacts_out.read().sequence == 5);
    // The target moved by a track, read at each step's time.
    let mut track = PoseTrack::default();
    track.push(Pose::IDENTITY, 0);
    track.push(Pose::from_translation(Vec3::X * 0.01), 16_000);
    target_in.write(ObjectPose::Track(track));
    assert_no_alloc(|| {
        world.step(30_000, None);
        world.step(31_000, Some(Instant::now() + Duration::from_micros(100)));
    });
    assert!(contacts_out.read().total_volume > 0.0 && contacts_out.read().sequence == 7);
}
