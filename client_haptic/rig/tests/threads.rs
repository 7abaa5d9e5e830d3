//! The threaded rig starts, runs both threads, exchanges data and stops (no timing claims here: rates
//! are measured by haptic-bench in release mode).

mod utils;

use std::time::{Duration, Instant};

use forcecomp::Material;
use glam::Vec3;
use haptic_common::{Delegator, OnCollision, Pose};
use haptic_rig::{HapticRig, ObjectSpec, Rendering, RigConfig, ToolSpec};
use haptico::sim::{SimConfig, SimDevice, TargetPath};
use haptico::{HapticEvents, presets};

/// Polls `done` every millisecond for up to 10 s (robust on a loaded CI machine).
fn eventually(mut done: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(10) {
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    false
}

#[test]
fn the_rig_runs_both_threads_and_broadcasts_collisions() {
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, 0.01, 0.0), Vec3::new(0.0, -0.002, 0.0), 0.1),
    );
    let hits = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
    let h = hits.clone();
    let mut on_collision = Delegator::<OnCollision>::new();
    on_collision.add_delegate(move |c: &OnCollision| {
        if !c.is_empty() {
            h.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
    });
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let rig = HapticRig::start(device, tool, RigConfig::default(), HapticEvents::default(), on_collision).expect("rig");
    rig.add_object(utils::slab_object(3)).expect("object");
    assert!(eventually(|| rig.haptic_telemetry().ticks > 50 && rig.telemetry().collision_sequence > 50));
    assert!(eventually(|| hits.load(std::sync::atomic::Ordering::Relaxed) > 0), "OnCollision fired with contacts");
    let mut samples = Vec::new();
    assert!(rig.drain_force_samples(&mut samples) > 50);
    rig.remove_object(3).expect("remove");
    let mut freed = 0;
    assert!(
        eventually(|| {
            freed += rig.collect_garbage();
            freed >= 1
        }),
        "the removed object came back to be freed here"
    );
    assert!(rig.stop().is_some());
}

#[test]
fn the_pipeline_under_the_rig_adds_replaces_removes_and_keeps_to_its_region_with_volumetric_rendering() {
    objects_come_and_go_in_the_one_pipeline(Rendering::Coupled);
}

#[test]
fn the_pipeline_under_the_rig_adds_replaces_removes_and_keeps_to_its_region_with_proxy_rendering() {
    objects_come_and_go_in_the_one_pipeline(Rendering::Proxy);
}

/// With the tool resting 2 mm deep in a slab: the slab's contacts come and go as it is added, replaced
/// far away, added again under another id, left outside the region, removed; what is replaced or removed
/// comes back to be freed; a fifth object is refused.
fn objects_come_and_go_in_the_one_pipeline(rendering: Rendering) {
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, -0.002, 0.0), Vec3::new(0.0, -0.002, 0.0), 0.1),
    );
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let config = RigConfig { rendering, ..RigConfig::default() };
    let rig = HapticRig::start(device, tool, config, HapticEvents::default(), Delegator::new()).expect("rig");
    // Contacts seen on a tick whose data came from a step after `after`.
    let touching = |after: u64| {
        let t = rig.telemetry();
        t.collision_sequence > after && t.contacts > 0
    };
    let apart = |after: u64| {
        let t = rig.telemetry();
        t.collision_sequence > after && t.contacts == 0
    };
    let now = || rig.telemetry().collision_sequence;
    assert!(
        eventually(|| rig.haptic_telemetry().ticks > 50 && rig.telemetry().contacts == 0),
        "nothing watched, nothing touched"
    );
    rig.add_object(utils::slab_object(3)).expect("add");
    assert!(eventually(|| touching(0)), "the slab is felt: {:?}", rig.telemetry());
    let far = ObjectSpec { pose: Pose::from_translation(Vec3::new(1.0, 0.0, 0.0)), ..utils::slab_object(3) };
    rig.add_object(far).expect("replace");
    let s = now();
    assert!(eventually(|| apart(s)), "the slab moved away with its replacement");
    rig.add_object(utils::slab_object(4)).expect("add another");
    let s = now();
    assert!(eventually(|| touching(s)), "the second slab is felt");
    rig.set_region(Some(collette::bounding_volume::Aabb::new(Vec3::splat(5.0), Vec3::splat(6.0)))).expect("region");
    let s = now();
    assert!(eventually(|| apart(s)), "outside the region nothing is checked");
    rig.set_region(None).expect("region");
    let s = now();
    assert!(eventually(|| touching(s)), "the region lifted");
    for id in [5, 6] {
        rig.add_object(ObjectSpec { pose: Pose::from_translation(Vec3::X * id as f32), ..utils::slab_object(id) })
            .expect("room for four");
    }
    assert!(matches!(rig.add_object(utils::slab_object(7)), Err(haptic_rig::RigError::TooManyObjects(4))));
    rig.remove_object(4).expect("remove");
    let s = now();
    assert!(eventually(|| apart(s)), "the removed slab is no longer felt");
    let mut freed = 0;
    assert!(
        eventually(|| {
            freed += rig.collect_garbage();
            freed >= 2
        }),
        "the replaced and the removed object came back to the game thread to be freed ({freed})"
    );
    let mut steps = Vec::new();
    assert!(rig.drain_collision_timings(&mut steps) > 10, "the pipeline records its steps");
    assert!(steps.windows(2).all(|w| w[1].sequence > w[0].sequence), "in order");
    assert!(rig.stop().is_some());
}
