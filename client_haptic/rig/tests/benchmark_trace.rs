//! The whole 35 s gemstone-over-bunny trajectory through the force stage (lockstep, smaller trees):
//! no command ever exceeds the device's clamps, no tick changes the force by more than the rate limit,
//! and nothing is ever NaN.

use std::time::Duration;

mod utils;

use collette::scene;
use forcecomp::{Material, SafetyConfig};
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectSpec, RigConfig, ToolSpec};
use haptico::presets;
use haptico::sim::{Keyframe, SimConfig, SimDevice, TargetPath};

#[test]
fn clamps_and_force_rate_hold_along_the_whole_benchmark_trace() {
    let (bunny_mesh, bunny, gem) = utils::small_bunny_scene();
    let path = scene::trajectory(&bunny_mesh);
    let keyframes = path.iter().map(|s| Keyframe { t_s: s.time_s, pose: s.tool }).collect();
    let specs = presets::phantom_premium_6dof();
    // A firm grip (800 N/m) that pushes harder than the device can push back.
    let mut sim = SimConfig::new(specs.clone());
    sim.hand.stiffness_n_per_m = 800.0;
    sim.hand.damping_ns_per_m = 8.0;
    let device = SimDevice::new(sim, TargetPath::Keyframes(keyframes));
    let safety = SafetyConfig::for_limits(specs.peak_force_n, specs.max_torque_nm);
    let config = RigConfig { safety: Some(safety), ..RigConfig::default() };
    // Very stiff materials, so that the deep stretch asks for more than the device's peak force.
    let stiff = Material { stiffness_n_per_m3: 1e10, damping_ns_per_m: 4.0, friction: 0.3, texture: None };
    let mut rig =
        Lockstep::new(device, ToolSpec::new(gem, stiff), &config, 2, Some(Duration::from_micros(400))).expect("rig");
    rig.add_object(ObjectSpec { id: 1, tree: bunny, pose: Pose::IDENTITY, material: stiff }).expect("bunny");

    let mut previous = haptic_common::ForceTorque::ZERO;
    let (mut max_f, mut max_tau, mut max_step, mut touched) = (0.0f32, 0.0f32, 0.0f32, 0u32);
    for i in 0..35_000u64 {
        let out = rig.tick(i * 1000);
        assert!(out.is_finite(), "tick {i}");
        max_f = max_f.max(out.force.length());
        max_tau = max_tau.max(out.torque.length());
        max_step = max_step.max((out.force - previous.force).length());
        touched += (rig.telemetry().contacts > 0) as u32;
        previous = out;
    }
    eprintln!(
        "max |F| {max_f:.3} N, max |tau| {max_tau:.4} N.m, max |dF| {max_step:.3} N/tick, {touched} ticks in contact"
    );
    assert!(touched > 10_000, "the path does touch the bunny");
    assert!(max_f <= specs.peak_force_n + 1e-4);
    assert!(max_tau <= specs.max_torque_nm + 1e-5);
    assert!(max_step <= safety.max_force_rate_n_per_s * 0.001 + 1e-4);
    assert!(rig.telemetry().safety.clamped > 0, "the clamp was actually needed: {:?}", rig.telemetry().safety);
    assert_eq!(rig.telemetry().safety.non_finite, 0);
}
