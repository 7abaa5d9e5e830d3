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

/// A rig whose 5 mm ball tool rests 2 mm below y = 0 at x = 0 (a simulated Touch held still), rendering
/// with `rendering`, `events` bound before its force stage.
fn resting_rig(rendering: Rendering, events: HapticEvents) -> HapticRig<SimDevice> {
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, -0.002, 0.0), Vec3::new(0.0, -0.002, 0.0), 0.1),
    );
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let config = RigConfig { rendering, ..RigConfig::default() };
    HapticRig::start(device, tool, config, events, Delegator::new()).expect("rig")
}

/// With the tool resting 2 mm deep in a slab: the slab's contacts come and go as it is added, replaced
/// far away, added again under another id, left outside the region, removed; what is replaced or removed
/// comes back to be freed; one object past `MAX_OBJECTS` is refused.
fn objects_come_and_go_in_the_one_pipeline(rendering: Rendering) {
    let rig = resting_rig(rendering, HapticEvents::default());
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
    for id in 5..5 + haptic_rig::MAX_OBJECTS as u32 - 2 {
        rig.add_object(ObjectSpec { pose: Pose::from_translation(Vec3::X * id as f32), ..utils::slab_object(id) })
            .expect("room for MAX_OBJECTS");
    }
    let full = rig.add_object(utils::slab_object(9999));
    assert!(matches!(full, Err(haptic_rig::RigError::TooManyObjects(haptic_rig::MAX_OBJECTS))), "{full:?}");
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

#[test]
fn a_moved_object_is_felt_where_it_went_and_the_telemetry_names_the_object_touched() {
    objects_move_and_are_named(Rendering::Coupled);
}

#[test]
fn a_moved_object_is_felt_where_it_went_with_proxy_rendering() {
    objects_move_and_are_named(Rendering::Proxy);
}

#[test]
fn without_a_force_stage_contacts_are_reported_and_only_the_delegates_push() {
    // A delegate's constant 0.1 N upwards (below the safety layer's engagement threshold): the only force.
    let mut events = HapticEvents::default();
    events.force_on_haptic_tick.add_delegate(|t: &haptic_common::ForceOnHapticTick| {
        t.add(haptic_common::ForceTorque { force: Vec3::Y * 0.1, torque: Vec3::ZERO })
    });
    let rig = resting_rig(Rendering::Off, events);
    rig.add_object(utils::slab_object(3)).expect("add");
    let touched = |t: &haptic_rig::RigTelemetry| t.objects().iter().any(|c| c.id == 3 && c.touching && c.volume > 0.0);
    assert!(eventually(|| touched(&rig.telemetry())), "the slab's contact is reported: {:?}", rig.telemetry());
    // Past the safety layer's fade-in, the output is the delegate's force alone: no contact force.
    assert!(eventually(|| (rig.telemetry().output.force - Vec3::Y * 0.1).length() < 1e-4), "{:?}", rig.telemetry());
    let t = rig.telemetry();
    assert!(touched(&t));
    assert_eq!(t.objects()[0].force, Vec3::ZERO, "no contact force without a force stage");
    assert!(rig.stop().is_some());
}

/// The tool rests 2 mm below y = 0 at x = 0; two slabs start far apart from it; moving the second one
/// under the tool makes it (and only it) touched, moving it away again ends the contact.
fn objects_move_and_are_named(rendering: Rendering) {
    let rig = resting_rig(rendering, HapticEvents::default());
    let away = |x: f32| Pose::from_translation(Vec3::new(x, -0.01, 0.0));
    rig.add_object(ObjectSpec { pose: away(0.5), ..utils::slab_object(1) }).expect("add");
    rig.add_object(ObjectSpec { pose: away(-0.5), ..utils::slab_object(2) }).expect("add");
    let touching = |id: u32| {
        let t = rig.telemetry();
        let ids: Vec<u32> = t.objects().iter().filter(|c| c.touching).map(|c| c.id).collect();
        ids == [id] && t.objects().iter().any(|c| c.id == id && c.force.y > 0.0)
    };
    // Objects far from the tool are not listed (the broad phase never queries them).
    let nothing = || rig.telemetry().objects().iter().all(|c| !c.touching);
    assert!(eventually(nothing), "both slabs far away: {:?}", rig.telemetry().objects());
    rig.set_object_pose(2, away(0.0)).expect("move");
    assert!(eventually(|| touching(2)), "the moved slab is under the tool: {:?}", rig.telemetry().objects());
    rig.set_object_pose(2, away(-0.5)).expect("move");
    assert!(eventually(nothing), "moved away again: {:?}", rig.telemetry().objects());
    assert!(matches!(rig.set_object_pose(9, away(0.0)), Err(haptic_rig::RigError::UnknownObject(9))));
    assert!(rig.stop().is_some());
}

/// Two slabs watched against each other (no tool in it): apart, then one moved half into the other, then
/// away; replacing one keeps the watch, removing one ends it; a pair with itself or an unknown object is
/// refused.
#[test]
fn a_watcher_between_two_objects_sees_them_overlap_where_the_game_moved_them() {
    let rig = resting_rig(Rendering::Coupled, HapticEvents::default());
    let at = |x: f32| Pose::from_translation(Vec3::new(x, 0.2, 0.0));
    rig.add_object(ObjectSpec { pose: at(0.5), ..utils::slab_object(1) }).expect("add");
    rig.add_object(ObjectSpec { pose: at(-0.5), ..utils::slab_object(2) }).expect("add");
    rig.watch_pair(1, 2).expect("watch");
    rig.watch_pair(2, 1).expect("the same pair again is no new watcher");
    assert!(matches!(rig.watch_pair(1, 1), Err(haptic_rig::RigError::SamePair(1))));
    assert!(matches!(rig.watch_pair(1, 9), Err(haptic_rig::RigError::UnknownObject(9))));
    let pairs = || {
        let mut out = Vec::new();
        rig.pair_contacts(&mut out);
        out
    };
    let measured = |touching: bool| {
        let p = pairs();
        p.len() == 1 && p[0].sequence > 0 && p[0].touching == touching && (p[0].a, p[0].b) == (1, 2)
    };
    assert!(eventually(|| measured(false)), "apart: {:?}", pairs());
    // Half of slab 2 (10 cm wide) inside slab 1: 5 x 2 x 10 cm overlap, 1e-4 m³.
    rig.set_object_pose(2, at(0.45)).expect("move");
    assert!(eventually(|| measured(true)), "overlapping: {:?}", pairs());
    let volume = pairs()[0].volume_m3;
    assert!((0.5e-4..2e-4).contains(&volume), "overlap {volume} m³");
    rig.set_object_pose(2, at(-0.5)).expect("move");
    assert!(eventually(|| measured(false)), "apart again: {:?}", pairs());
    // Replaced (a new tree under the same id, placed over slab 1): still watched.
    rig.add_object(ObjectSpec { pose: at(0.45), ..utils::slab_object(2) }).expect("replace");
    assert!(eventually(|| measured(true)), "the replaced slab is still watched: {:?}", pairs());
    rig.remove_object(1).expect("remove");
    assert!(pairs().is_empty(), "removing an object ends its watchers");
    rig.unwatch_pair(1, 2).expect("nothing left to unwatch is no error");
    assert!(rig.stop().is_some());
}
