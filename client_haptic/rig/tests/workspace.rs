//! A real device's grip read outside its workspace (not homed, not centred, or a broken reading) gets no
//! force from the rig, in either rendering; inside, it feels the contact as usual.

mod utils;

use forcecomp::{Material, SafetyConfig, Workspace};
use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectSpec, Rendering, RigConfig, RigTelemetry, ToolSpec};
use haptico::presets;
use haptico::sim::{SimConfig, SimDevice, TargetPath};

/// A Touch pressed 4 mm into a slab for 1.5 s, with forces kept to `workspace`: the telemetry at the end
/// and the largest force output.
fn press(rendering: Rendering, workspace: Workspace) -> (RigTelemetry, f32) {
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, 0.02, 0.0), Vec3::new(0.0, -0.004, 0.0), 0.5),
    );
    let safety = SafetyConfig { ramp_in_s: 0.05, ..SafetyConfig::for_limits(3.3, 0.0) };
    let config = RigConfig { safety: Some(safety), workspace: Some(workspace), rendering, ..RigConfig::default() };
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let mut rig = Lockstep::new(device, tool, &config, 1, None).expect("rig");
    let slab = Material { stiffness_n_per_m3: 1e9, damping_ns_per_m: 1.0, friction: 0.0, texture: None };
    let pose = Pose::from_translation(Vec3::new(0.0, -0.01, 0.0));
    rig.add_object(ObjectSpec { id: 7, tree: utils::slab(), pose, material: slab }).expect("object");
    let mut most = 0.0f32;
    for tick in 0..1500u64 {
        most = most.max(rig.tick(tick * 1000).force.length());
    }
    (rig.telemetry(), most)
}

#[test]
fn a_grip_read_outside_the_workspace_feels_nothing_and_inside_it_feels_the_contact_in_both_renderings() {
    for rendering in [Rendering::Coupled, Rendering::Proxy] {
        let around_the_hand = Workspace { centre: Vec3::ZERO, radius_m: 0.05 };
        let (inside, felt) = press(rendering, around_the_hand);
        assert!(felt > 0.1 && !inside.outside_workspace, "{rendering:?}: {felt} N inside");
        assert_eq!(inside.safety.outside_workspace, 0, "{rendering:?}");

        // The same press, the device's reach 20 cm away: as a Falcon that is not homed reads.
        let elsewhere = Workspace { centre: Vec3::new(0.0, 0.2, 0.0), radius_m: 0.05 };
        let (outside, felt) = press(rendering, elsewhere);
        assert_eq!(felt, 0.0, "{rendering:?}: no force at all");
        assert!(outside.outside_workspace, "{rendering:?}: the telemetry says why");
        assert_eq!(outside.safety.outside_workspace, 1500, "{rendering:?}: every tick");
    }
}
