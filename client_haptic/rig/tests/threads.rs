//! The threaded rig starts, runs both threads, exchanges data and stops (no timing claims here: rates
//! are measured by haptic-bench in release mode).

mod utils;

use std::time::{Duration, Instant};

use forcecomp::Material;
use glam::Vec3;
use haptic_common::{Delegator, OnCollision, Pose};
use haptic_rig::{HapticRig, ObjectSpec, RigConfig, ToolSpec};
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
fn the_rig_also_runs_on_collettes_pipeline_thread() {
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, 0.01, 0.0), Vec3::new(0.0, -0.002, 0.0), 0.1),
    );
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let slab = ObjectSpec {
        id: 3,
        tree: utils::slab(),
        pose: Pose::from_translation(Vec3::new(0.0, -0.01, 0.0)),
        material: Material::default(),
    };
    let rig = HapticRig::start_with_collette(device, tool, vec![slab], RigConfig::default(), HapticEvents::default())
        .expect("rig");
    assert!(
        eventually(|| rig.telemetry().collision_sequence > 50 && rig.telemetry().contacts > 0),
        "{:?}",
        rig.telemetry()
    );
    let tel = rig.telemetry();
    assert!(tel.data_age_us < 1_000_000, "{tel:?}");
    assert!(matches!(rig.pause_collision(true), Err(haptic_rig::RigError::Unsupported(_))));
    assert!(rig.stop().is_some());
}
