//! The simulated hand pushing a ball tool into a stiff slab for seconds: with the rig's virtual coupling
//! the loop gains no energy (it settles); rendering the same contact directly oscillates.

mod utils;

use forcecomp::{Material, SafetyConfig};
use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectSpec, Rendering, RigConfig, ToolSpec};
use haptico::presets;
use haptico::sim::{SimConfig, SimDevice, TargetPath};

/// Runs `seconds` of pushing 4 mm into the slab; returns per-tick (true y, kinetic energy, |F|).
fn push_into_wall(rendering: Rendering, seconds: f64) -> Vec<(f32, f32, f32)> {
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, 0.02, 0.0), Vec3::new(0.0, -0.004, 0.0), 1.0),
    );
    let stiff = Material { stiffness_n_per_m3: 1e9, damping_ns_per_m: 1.0, friction: 0.0, texture: None };
    let config = RigConfig {
        rendering,
        safety: Some(SafetyConfig { ramp_in_s: 0.05, ..SafetyConfig::for_limits(3.3, 0.0) }),
        ..RigConfig::default()
    };
    let tool = ToolSpec::new(utils::ball_tool(), Material { stiffness_n_per_m3: 1e9, ..Material::default() });
    let mut rig = Lockstep::new(device, tool, &config, 1, None).expect("rig");
    rig.add_object(ObjectSpec {
        id: 1,
        tree: utils::slab(),
        pose: Pose::from_translation(Vec3::new(0.0, -0.01, 0.0)),
        material: stiff,
    })
    .expect("object");
    let ticks = (seconds * 1000.0) as u64;
    let mut out = Vec::with_capacity(ticks as usize);
    for i in 0..ticks {
        let f = rig.tick(i * 1000);
        out.push((rig.device().true_position().y, rig.device().kinetic_energy_j(), f.force.length()));
    }
    out
}

fn max_in(s: &[(f32, f32, f32)], f: impl Fn(&(f32, f32, f32)) -> f32) -> f32 {
    s.iter().map(f).fold(0.0, f32::max)
}

#[test]
fn with_the_coupling_a_stiff_wall_gains_no_energy_and_settles() {
    let run = push_into_wall(Rendering::Coupled, 4.0);
    let (second_last, last) = (&run[2000..3000], &run[3000..4000]);
    let ke_before = max_in(second_last, |s| s.1);
    let ke_last = max_in(last, |s| s.1);
    let y_min = last.iter().map(|s| s.0).fold(f32::INFINITY, f32::min);
    let y_max = last.iter().map(|s| s.0).fold(f32::NEG_INFINITY, f32::max);
    eprintln!(
        "coupled: KE {ke_before:.2e} -> {ke_last:.2e} J, y in [{y_min:.5}, {y_max:.5}], |F| {:.3} N",
        last[999].2
    );
    assert!(ke_last <= ke_before + 1e-7, "energy grew: {ke_before} -> {ke_last}");
    assert!(ke_last < 1e-6, "no sustained oscillation: {ke_last} J");
    assert!(y_max - y_min < 2e-4, "settled: {y_min}..{y_max}");
    assert!(last[999].2 > 0.5, "the wall pushes back: {} N", last[999].2);
}

#[test]
fn rendering_the_same_wall_directly_oscillates() {
    let run = push_into_wall(Rendering::Direct, 4.0);
    let last = &run[3000..4000];
    let ke_last = max_in(last, |s| s.1);
    eprintln!("direct: KE max in the last second {ke_last:.2e} J");
    assert!(ke_last > 1e-5, "the simulated hand shows the instability: {ke_last} J");
}
