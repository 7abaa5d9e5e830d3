//! One collision step of a whole scene: a tool among 256 objects scattered in a 20 cm box (1.2 cm balls
//! and boxes of 300 spheres), touching a few, watched by one scene watcher (the tool against every
//! object), with the broad phase and without it, beside the same tool against one object.
//!
//! `cargo bench -p collette_ist --bench scene_step` (criterion: medians of exact, unbudgeted steps on
//! one thread; docs/haptics.md, "Whole scenes").

use std::sync::Arc;

use collette::pipeline::{
    CollisionConfig, CollisionHandle, CollisionStepper, PoseWriter, SceneReader, TimedPose, pipeline,
};
use collette::shape::{box_buffers, uv_sphere_buffers};
use collette::{BuildOptions, InnerSphereTree, Pose, TriMesh, build};
use criterion::Criterion;
use glam::{Quat, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn tree(buffers: (Vec<Vec3>, Vec<[u32; 3]>), spheres: usize) -> Arc<InnerSphereTree> {
    let mesh = TriMesh::new(buffers.0, buffers.1).expect("valid mesh");
    Arc::new(build(&mesh, &BuildOptions::spheres(spheres), &mut |_| {}).expect("builds").0)
}

/// What a benchmarked scene is made of (the handle and writers only kept alive).
struct Scene {
    stepper: CollisionStepper,
    reader: SceneReader,
    _handle: CollisionHandle,
    _writers: Vec<PoseWriter>,
}

/// A scene of `objects` objects and the tool at the origin, stepped by hand; the first object is at the
/// origin too (the tool presses into it), the others scattered.
fn scene(objects: usize, broad_phase: bool) -> Scene {
    let shapes = [tree(uv_sphere_buffers(0.006, 12, 16), 300), tree(box_buffers(Vec3::splat(0.006)), 300)];
    let config = CollisionConfig {
        max_objects: objects + 1,
        max_watchers: 1,
        command_capacity: 1024,
        broad_phase,
        ..Default::default()
    };
    let (mut handle, stepper) = pipeline(&config, haptic_common::Delegator::new());
    let mut tool =
        handle.add_object(tree(box_buffers(Vec3::new(0.01, 0.003, 0.003)), 500), Pose::IDENTITY).expect("slot");
    let mut rng = ChaCha8Rng::seed_from_u64(0x2545_f491);
    let mut roll = || rng.random::<f32>();
    let writers: Vec<PoseWriter> = (0..objects)
        .map(|i| {
            let scattered = Vec3::new(roll(), roll(), roll()) * 0.2 - Vec3::splat(0.1);
            let at = if i == 0 { Vec3::ZERO } else { scattered };
            let pose = Pose::new(at, Quat::from_rotation_y(roll() * 3.0));
            let still = TimedPose { pose, timestamp_us: u64::MAX, reach: 0.0 };
            handle.add_object_at(shapes[i % 2].clone(), still).expect("slot")
        })
        .collect();
    let reader = handle.add_scene_watcher(tool.id()).expect("slot");
    tool.set(Pose::IDENTITY, 0);
    Scene { stepper, reader, _handle: handle, _writers: std::iter::once(tool).chain(writers).collect() }
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    let mut group = c.benchmark_group("scene_step");
    for (name, objects, broad_phase) in
        [("256_objects", 256, true), ("256_objects_no_broad_phase", 256, false), ("1_object", 1, true)]
    {
        let Scene { mut stepper, mut reader, .. } = scene(objects, broad_phase);
        let mut t = 0u64;
        group.bench_function(name, |b| {
            b.iter(|| {
                t += 1000;
                stepper.step(t, false, || t)
            })
        });
        let seen = reader.latest();
        eprintln!("scene_step/{name}: {} objects touched, {} contacts", seen.touched().len(), seen.contacts().len());
    }
    group.finish();
    c.final_summary();
}
