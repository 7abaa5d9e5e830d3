//! A whole scene in the collision pipeline: 256 objects, some moved by the game through pose tracks, a
//! tool sweeping through them, watchers between the tool and every object and between objects. Every
//! step's published result is compared with the same query run directly on the same poses, pair by
//! pair: the broad phase may skip only pairs that have nothing to report. The scene watchers (the tool
//! against everything, in one buffer) and the summary watchers must say what the per-pair ones say.

use std::sync::Arc;

use collette::pipeline::{CollisionConfig, ContactReader, PoseTrack, PoseWriter, TimedPose, TrackTiming, pipeline};
use collette::shape::{box_buffers, torus_buffers, uv_sphere_buffers};
use collette::{
    Budget, BuildOptions, ContactSet, InnerSphereTree, OverlapResult, Pose, QueryWorkspace, TriMesh, build,
    overlap_budgeted,
};
use glam::{Quat, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const OBJECTS: usize = 256;

fn tree(buffers: (Vec<Vec3>, Vec<[u32; 3]>)) -> Arc<InnerSphereTree> {
    let mesh = TriMesh::new(buffers.0, buffers.1).expect("valid mesh");
    Arc::new(build(&mesh, &BuildOptions::spheres(120), &mut |_| {}).expect("builds").0)
}

/// The query a step runs for a pair (exact: no time budget), run directly.
fn query(
    a: &InnerSphereTree,
    pa: &Pose,
    b: &InnerSphereTree,
    pb: &Pose,
    ws: &mut QueryWorkspace,
    set: &mut ContactSet,
) -> OverlapResult {
    overlap_budgeted(a, pa, b, pb, Budget::Unlimited, ws, set)
}

struct Placed {
    tree: Arc<InnerSphereTree>,
    writer: PoseWriter,
    /// Where it rests, or its track when the game moves it.
    rest: Pose,
    track: Option<PoseTrack>,
}

impl Placed {
    fn pose_at(&self, t_us: u64) -> Pose {
        self.track.and_then(|t| t.at(t_us)).map_or(self.rest, |m| m.pose)
    }
}

#[test]
fn a_tool_sweeping_through_256_objects_finds_every_contact_the_direct_queries_find() {
    sweep(true);
}

#[test]
fn without_the_broad_phase_every_pair_is_queried_and_the_results_are_the_same() {
    sweep(false);
}

/// The sweep, with or without the broad phase.
fn sweep(broad_phase: bool) {
    let shapes = [
        tree(box_buffers(Vec3::new(0.03, 0.02, 0.025))),
        tree(uv_sphere_buffers(0.03, 10, 16)),
        tree(torus_buffers(0.03, 0.01, 16, 10)),
    ];
    let tool_tree = tree(box_buffers(Vec3::new(0.06, 0.015, 0.015)));
    let config = CollisionConfig {
        max_objects: OBJECTS + 1,
        max_watchers: 2 * OBJECTS + 2 * 64 + 2,
        command_capacity: 1024,
        broad_phase,
        ..Default::default()
    };
    let (mut handle, mut stepper) = pipeline(&config, haptic_common::Delegator::new());
    let mut tool = handle.add_object(tool_tree.clone(), Pose::IDENTITY).expect("slot");
    // 256 objects on a 16 × 16 grid about 0.1 apart (jittered, turned), every eighth moved by the game.
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed);
    let mut roll = || rng.random::<f32>();
    let mut placed: Vec<Placed> = Vec::new();
    for i in 0..OBJECTS {
        let jitter = Vec3::new(roll() - 0.5, roll() - 0.5, roll() - 0.5) * 0.04;
        let at = match placed.last() {
            // Every fourth object's right-hand neighbour leans on it (their pair is watched).
            Some(left) if i % 4 == 1 => left.rest.translation + Vec3::X * 0.05 + jitter * 0.2,
            _ => Vec3::new((i % 16) as f32 * 0.1, (i / 16) as f32 * 0.1, 0.0) + jitter,
        };
        let rest = Pose::new(at, Quat::from_euler(glam::EulerRot::XYZ, roll() * 3.0, roll() * 3.0, 0.0));
        let tree = shapes[i % 3].clone();
        let still = TimedPose { pose: rest, timestamp_us: u64::MAX, reach: 0.0 };
        let writer = handle.add_object_at(tree.clone(), still).expect("an object slot");
        let track = (i % 8 == 0).then(|| PoseTrack::new(TrackTiming::default()));
        placed.push(Placed { tree, writer, rest, track });
    }
    // The tool against every object, and each object against its right-hand neighbour for 64 of them.
    let mut tool_watchers: Vec<ContactReader> =
        placed.iter().map(|p| handle.add_watcher(tool.id(), p.writer.id()).expect("a watcher slot")).collect();
    // The same through one scene watcher, and the tool's origin's near spheres per object and for the
    // whole scene.
    let mut scene = handle.add_scene_watcher(tool.id()).expect("a watcher slot");
    let mut near: Vec<_> =
        placed.iter().map(|p| handle.add_near_watcher(tool.id(), p.writer.id()).expect("a watcher slot")).collect();
    let mut scene_near = handle.add_scene_near_watcher(tool.id()).expect("a watcher slot");
    let pairs: Vec<(usize, usize)> = (0..64).map(|k| (k * 4, k * 4 + 1)).collect();
    let mut pair_watchers: Vec<ContactReader> = pairs
        .iter()
        .map(|&(a, b)| handle.add_watcher(placed[a].writer.id(), placed[b].writer.id()).expect("a watcher slot"))
        .collect();
    let mut summaries: Vec<_> = pairs
        .iter()
        .map(|&(a, b)| handle.add_summary_watcher(placed[a].writer.id(), placed[b].writer.id()).expect("a slot"))
        .collect();

    let (mut ws, mut direct) = (QueryWorkspace::new(), ContactSet::new());
    let (mut touched, mut pair_touches, mut culled, mut queried, mut near_spheres) = (0, 0, 0u64, 0u64, 0);
    // The tool sweeps along each row in turn (0.5 m/s), the moving objects bob at 60 Hz frames.
    for step in 0..1500u64 {
        let t_us = step * 1000;
        let row = (step / 100) as f32;
        let x = (step % 100) as f32 * 0.016;
        let tool_pose = Pose::new(Vec3::new(x, row * 0.1 + 0.02, 0.005), Quat::from_rotation_z(0.3));
        tool.set_with_reach(tool_pose, t_us, 0.02);
        if step % 16 == 0 {
            for p in placed.iter_mut() {
                if let Some(track) = &mut p.track {
                    let bob = Vec3::Z * 0.02 * (t_us as f32 * 1e-6 * 6.0).sin();
                    track.push(Pose::new(p.rest.translation + bob, p.rest.rotation), t_us);
                    p.writer.set_track(track);
                }
            }
        }
        let report = stepper.step(t_us, false, || t_us);
        culled += report.culled as u64;
        queried += report.queried as u64;
        let (scene, scene_near) = (scene.latest(), scene_near.latest());
        assert_eq!((scene.sequence, scene.overflow, scene_near.overflow), (step + 1, 0, 0));
        let mut listed = 0;
        for ((p, reader), near) in placed.iter().zip(&mut tool_watchers).zip(&mut near) {
            let got = reader.latest();
            if !got.is_empty() || got.total_volume > 0.0 {
                let id = p.writer.id().0;
                let touched = scene.touched().iter().find(|t| t.object == id);
                let touched = touched.expect("every touched object is in the scene watcher's set");
                listed += 1;
                assert_eq!(scene.contacts_of(touched), got.as_slice(), "step {step}");
                assert_eq!(touched.total_volume, got.total_volume);
            }
            let mine: Vec<_> = scene_near.as_slice().iter().filter(|s| s.object == p.writer.id().0).collect();
            let theirs: Vec<_> = near.latest().as_slice().iter().collect();
            assert_eq!(mine, theirs, "step {step}: the scene's near spheres of each object are its own");
            near_spheres += theirs.len();
            let want = query(&tool_tree, &tool_pose, &p.tree, &p.pose_at(t_us), &mut ws, &mut direct);
            assert_eq!((got.len(), got.total_volume), (direct.len(), want.total_volume), "step {step}");
            assert_eq!(got.sequence, step + 1);
            touched += !got.is_empty() as u32;
        }
        assert_eq!(scene.touched().len(), listed, "and no other");
        for ((&(a, b), reader), summary) in pairs.iter().zip(&mut pair_watchers).zip(&mut summaries) {
            let (pa, pb) = (placed[a].pose_at(t_us), placed[b].pose_at(t_us));
            let want = query(&placed[a].tree, &pa, &placed[b].tree, &pb, &mut ws, &mut direct);
            let got = reader.latest();
            assert_eq!((got.len(), got.total_volume), (direct.len(), want.total_volume), "step {step}: {a}-{b}");
            pair_touches += !got.is_empty() as u32;
            let summary = summary.latest();
            assert_eq!((summary.pairs, summary.total_volume), (got.len() as u32, got.total_volume));
        }
    }
    assert!(touched > 300, "the sweep touches objects: {touched} contacts found over the sweep");
    assert!(pair_touches > 1000, "neighbours touch: {pair_touches}");
    assert!(near_spheres > 1000, "the tool's origin passes near objects: {near_spheres} spheres over the sweep");
    // Per step: the tool against each object three times (one watcher each, the scene watcher, the
    // near watchers and the scene near watcher: four), and each pair twice (contacts and summary).
    let watched = 1500 * (4 * OBJECTS + 2 * pairs.len()) as u64;
    assert_eq!(culled + queried, watched, "every pair was either queried or culled");
    // The neighbours lean on each other (always queried); the tool is near a few objects at a time.
    let tool_pairs = 4 * 1500 * OBJECTS as u64;
    if broad_phase {
        assert!(
            culled > tool_pairs * 9 / 10,
            "most of the tool's pairs are never queried: {culled} of {watched} culled"
        );
    } else {
        assert_eq!(culled, 0, "without the broad phase every pair is queried");
    }
}
