//! When collision detection stops delivering, the safety layer's watchdog fades the force to zero.

mod utils;

use forcecomp::{Material, SafetyConfig};
use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectSpec, RigConfig, ToolSpec};
use haptico::presets;
use haptico::sim::{SimConfig, SimDevice, TargetPath};

/// A lockstep rig (a collision step every `collision_every` ticks) whose ball tool moves down onto a
/// stiff slab (object 7, its top at y = 0), with a 50 ms ramp-in; and a slab `id` whose top is at `y`.
fn pressing(collision_every: u64) -> (Lockstep<SimDevice>, impl Fn(u32, f32) -> ObjectSpec) {
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, 0.02, 0.0), Vec3::new(0.0, -0.004, 0.0), 0.5),
    );
    let safety = SafetyConfig { ramp_in_s: 0.05, ..SafetyConfig::for_limits(3.3, 0.0) };
    let config = RigConfig { safety: Some(safety), ..RigConfig::default() };
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let mut rig = Lockstep::new(device, tool, &config, collision_every, None).expect("rig");
    let slab = Material { stiffness_n_per_m3: 1e9, damping_ns_per_m: 1.0, friction: 0.0, texture: None };
    let spec = move |id, y| ObjectSpec {
        id,
        tree: utils::slab(),
        pose: Pose::from_translation(Vec3::new(0.0, y - 0.01, 0.0)),
        material: slab,
    };
    rig.add_object(spec(7, 0.0)).expect("object");
    (rig, spec)
}

#[test]
fn pausing_the_collision_thread_ramps_the_force_to_zero() {
    let (mut rig, _) = pressing(1);
    let mut t = 0u64;
    for _ in 0..1500 {
        rig.tick(t);
        t += 1000;
    }
    let pushing = rig.telemetry().output.force.length();
    assert!(pushing > 0.3, "in contact before the pause: {pushing} N");

    rig.pause_collision(true);
    let mut forces = Vec::new();
    for _ in 0..200 {
        forces.push(rig.tick(t).force.length());
        t += 1000;
    }
    // Still full force within the 32 ms timeout, then down to zero within the 50 ms ramp (+ rate limit).
    assert!(forces[20] > 0.5 * pushing, "{}", forces[20]);
    assert!(forces[120] == 0.0, "{:?}", &forces[80..120]);
    assert!(forces[120..].iter().all(|&f| f == 0.0));
    let tel = rig.telemetry();
    assert!(tel.safety.stale > 0 && tel.safety_gain == 0.0);

    rig.pause_collision(false);
    for _ in 0..3000 {
        rig.tick(t);
        t += 1000;
    }
    assert!(rig.telemetry().output.force.length() > 0.3, "forces come back once data is fresh");
}

#[test]
fn placing_an_object_keeps_the_force_whole_until_its_first_collision_step() {
    // A collision step every 10 ticks: a watcher added just after one publishes 9 ticks later.
    let (mut rig, spec) = pressing(10);
    let mut t = 0u64;
    for _ in 0..1501 {
        rig.tick(t);
        t += 1000;
    }
    let pushing = rig.telemetry().output.force.length();
    let stale_before = rig.telemetry().safety.stale;
    assert!(pushing > 0.3, "in contact: {pushing} N");

    // A second object, far below, placed while the tool presses on the first.
    rig.add_object(spec(8, -0.49)).expect("object");
    let forces: Vec<f32> = (0..300)
        .map(|_| {
            let f = rig.tick(t).force.length();
            t += 1000;
            f
        })
        .collect();
    let weakest = forces.iter().copied().fold(f32::INFINITY, f32::min);
    assert!(weakest > 0.9 * pushing, "the force dipped to {weakest} N of {pushing} N while the new watcher was silent");
    let tel = rig.telemetry();
    assert_eq!((tel.safety.stale, tel.safety_gain), (stale_before, 1.0), "the watchdog stayed quiet");
}
