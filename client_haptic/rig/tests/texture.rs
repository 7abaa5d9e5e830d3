//! Ridges through the rig (lockstep, exact), in both renderings: a stroke along a ribbed slab feels a
//! push that repeats once per ridge spacing (a smooth slab gives none), and the ridges are passive on
//! the simulated hand: over a closed stroke they give back no more energy than they took, and a hand
//! resting on a flank settles.

mod utils;

use forcecomp::{Material, SafetyConfig, Texture};
use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectSpec, ProxyRendering, Rendering, RigConfig, ToolSpec};
use haptico::presets;
use haptico::sim::{Keyframe, SimConfig, SimDevice, TargetPath};

/// Ridges 3 mm apart with grooves 0.3 mm deep, repeating along x.
const SPACING: f32 = 0.003;
const GROOVES: f32 = 0.0003;

/// One tick of a run: the hand's true position and velocity, and the force on it.
struct Tick {
    position: Vec3,
    velocity: Vec3,
    force: Vec3,
}

/// The slab's material: 300 N/m through the proxy, ~1 N at 0.5 mm under the 5 mm ball.
fn material(ribbed: bool, friction: f32) -> Material {
    let texture = ribbed.then(|| Texture { axis: Vec3::X, ..Texture::ribs(SPACING, GROOVES, 3000.0) });
    Material { stiffness_n_per_m3: 3e8, damping_ns_per_m: 0.0, friction, texture }
}

/// Runs the hand along `keys` over the slab (top face at y = 0) and records every tick.
fn run(rendering: Rendering, material: Material, keys: Vec<Keyframe>, seconds: f64) -> Vec<Tick> {
    let device = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::Keyframes(keys));
    let config = RigConfig {
        rendering,
        proxy: ProxyRendering { volume_per_depth_m2: 1e-6, damping_ns_per_m: 0.0, ..Default::default() },
        safety: Some(SafetyConfig { ramp_in_s: 0.05, ..SafetyConfig::for_limits(3.3, 0.0) }),
        ..RigConfig::default()
    };
    let tool = ToolSpec::new(utils::ball_tool(), Material { stiffness_n_per_m3: 3e12, texture: None, ..material });
    let mut rig = Lockstep::new(device, tool, &config, 1, None).expect("rig");
    // The finer slab: the 1,500-sphere one fills only half its volume, and once its spheres are weighted
    // (each standing for its share of the gaps) the bumps of its surface spheres, 5-6 mm apart, push
    // as hard through the volumetric rendering as the 0.3 mm ridges do (docs/collette.md, Limits).
    let slab = ObjectSpec {
        id: 1,
        tree: utils::fine_slab(),
        pose: Pose::from_translation(Vec3::new(0.0, -0.01, 0.0)),
        material,
    };
    rig.add_object(slab).expect("slab");
    (0..(seconds * 1000.0) as u64)
        .map(|i| {
            let force = rig.tick(i * 1000).force;
            Tick { position: rig.device().true_position(), velocity: rig.device().true_velocity(), force }
        })
        .collect()
}

fn key(t_s: f64, x: f32, y: f32) -> Keyframe {
    Keyframe { t_s, pose: Pose::from_translation(Vec3::new(x, y, 0.0)) }
}

/// Where the hand aims to press: into the slab far enough for ~1 N through either rendering.
fn press_y(rendering: Rendering) -> f32 {
    match rendering {
        Rendering::Proxy => -0.0015,
        _ => -0.0035,
    }
}

/// Press at x = −15 mm, stroke to +15 mm from 1.5 s to 3.5 s (15 mm/s), stop there.
fn stroke(rendering: Rendering, ribbed: bool) -> Vec<Tick> {
    let y = press_y(rendering);
    let keys = vec![key(0.0, -0.015, 0.01), key(1.0, -0.015, y), key(1.5, -0.015, y), key(3.5, 0.015, y)];
    run(rendering, material(ribbed, 0.2), keys, 3.6)
}

/// Amplitude of the along-stroke force's component that repeats every `period` of the hand's travel, N
/// (a Fourier coefficient over position, for samples in `slide`).
fn amplitude_at(slide: &[Tick], period: f32) -> f32 {
    let mean = slide.iter().map(|t| t.force.x).sum::<f32>() / slide.len() as f32;
    let (mut c, mut s, mut travel) = (0.0f32, 0.0f32, 0.0f32);
    for w in slide.windows(2) {
        let dx = (w[1].position.x - w[0].position.x).abs();
        let phase = std::f32::consts::TAU * w[1].position.x / period;
        c += (w[1].force.x - mean) * phase.cos() * dx;
        s += (w[1].force.x - mean) * phase.sin() * dx;
        travel += dx;
    }
    2.0 * c.hypot(s) / travel.max(f32::MIN_POSITIVE)
}

fn the_ridges_are_felt_once_per_spacing(rendering: Rendering) {
    let ribbed = stroke(rendering, true);
    let smooth = stroke(rendering, false);
    let touching = ribbed[1800..3400].iter().filter(|t| t.force.y > 0.3).count();
    assert!(touching > 1500, "{rendering:?}: the stroke stayed pressed on the slab ({touching} of 1600 ticks)");
    let (slide, plain) = (&ribbed[1800..3400], &smooth[1800..3400]);
    let (r, r_short, r_long) =
        (amplitude_at(slide, SPACING), amplitude_at(slide, 0.6 * SPACING), amplitude_at(slide, 1.7 * SPACING));
    let m = amplitude_at(plain, SPACING);
    eprintln!(
        "{rendering:?}: ribbed {r:.3} N at the spacing ({r_short:.3} at 0.6x, {r_long:.3} at 1.7x); smooth {m:.3} N"
    );
    assert!(r > 0.1, "{rendering:?}: the ridges push back and forth: {r} N");
    assert!(r > 3.0 * r_short.max(r_long), "{rendering:?}: once per spacing, not at another period");
    assert!(m < 0.2 * r, "{rendering:?}: the smooth slab has no such push: {m} N");
}

#[test]
fn a_stroke_over_ridges_through_the_proxy_is_pushed_once_per_ridge() {
    the_ridges_are_felt_once_per_spacing(Rendering::Proxy);
}

#[test]
fn a_stroke_over_ridges_through_the_volumetric_force_is_pushed_once_per_ridge() {
    the_ridges_are_felt_once_per_spacing(Rendering::Coupled);
}

/// Work the rendered force did on the hand over a run, J, and the work moved either way.
fn work_on_the_hand(run: &[Tick]) -> (f64, f64) {
    let (mut net, mut gross) = (0.0f64, 0.0f64);
    for t in run {
        let dw = f64::from(t.force.dot(t.velocity)) * 1e-3;
        net += dw;
        gross += dw.abs();
    }
    (net, gross)
}

fn the_ridges_are_passive(rendering: Rendering) {
    // Frictionless and undamped, so only the ridges could give energy back: in, along 5.4 ridges and
    // back, out to where the hand began, then 1.5 s at rest.
    let y = press_y(rendering);
    let far = -0.008 + 5.4 * SPACING;
    let keys = vec![
        key(0.0, -0.008, 0.01),
        key(1.0, -0.008, y),
        key(2.0, far, y),
        key(3.0, -0.008, y),
        key(3.5, -0.008, 0.01),
    ];
    let ribbed = run(rendering, material(true, 0.0), keys.clone(), 5.0);
    let smooth = run(rendering, material(false, 0.0), keys, 5.0);
    let (net, gross) = work_on_the_hand(&ribbed);
    let peak = |r: &[Tick]| r.iter().map(|t| t.force.length()).fold(0.0, f32::max);
    let rest_ke = ribbed[4000..].iter().map(|t| 0.5 * 0.15 * t.velocity.length_squared()).fold(0.0, f32::max);
    eprintln!(
        "{rendering:?}: net work on the hand {net:.2e} J of {gross:.2e} J; peak {:.2} N (smooth {:.2} N); KE at rest {rest_ke:.1e} J",
        peak(&ribbed),
        peak(&smooth)
    );
    assert!(gross > 1e-3, "the stroke pressed the ridges");
    assert!(net <= 0.01 * gross, "{rendering:?}: the ridges gave back more than they took: {net} of {gross} J");
    assert!(peak(&ribbed) <= 1.3 * peak(&smooth) + 0.05, "{rendering:?}: bounded by the smooth force and the slope");
    assert!(rest_ke < 1e-7, "{rendering:?}: the hand came to rest: {rest_ke} J");
}

#[test]
fn ridges_through_the_proxy_give_the_hand_no_energy() {
    the_ridges_are_passive(Rendering::Proxy);
}

#[test]
fn ridges_through_the_volumetric_force_give_the_hand_no_energy() {
    the_ridges_are_passive(Rendering::Coupled);
}
