//! When collision detection stops delivering, the safety layer's watchdog fades the force to zero.

mod utils;

use forcecomp::{Material, SafetyConfig};
use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectSpec, RigConfig, ToolSpec};
use haptico::presets;
use haptico::sim::{SimConfig, SimDevice, TargetPath};

#[test]
fn pausing_the_collision_thread_ramps_the_force_to_zero() {
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, 0.02, 0.0), Vec3::new(0.0, -0.004, 0.0), 0.5),
    );
    let safety = SafetyConfig { ramp_in_s: 0.05, ..SafetyConfig::for_limits(3.3, 0.0) };
    let config = RigConfig { safety: Some(safety), ..RigConfig::default() };
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let mut rig = Lockstep::new(device, tool, &config, 1, None).expect("rig");
    let slab = Material { stiffness_n_per_m3: 1e9, damping_ns_per_m: 1.0, friction: 0.0, texture: None };
    rig.add_object(ObjectSpec {
        id: 7,
        tree: utils::slab(),
        pose: Pose::from_translation(Vec3::new(0.0, -0.01, 0.0)),
        material: slab,
    })
    .expect("object");
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
