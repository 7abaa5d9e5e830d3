//! 3-DOF proxy rendering through the rig (lockstep, exact): a tip pressed into a flat slab sinks only as
//! far as the spring allows and is pushed straight out; dragged along, it slides with Coulomb friction.

mod utils;

use collette::shape::lens_volume;
use forcecomp::Material;
use forcecomp::proxy::SURFACE_CAP;
use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectSpec, ProxyRendering, Rendering, RigConfig, ToolSpec};
use haptico::presets;
use haptico::sim::{Keyframe, SimConfig, SimDevice, TargetPath};

/// Proxy spring of the test: 3e7 N/m³ × 1e-5 m² = 300 N/m (the Touch allows more).
const K: f32 = 300.0;
const MU: f32 = 0.5;

/// Radius of the tip (the rig's default).
const TIP: f32 = 0.004;

/// Where the tip's centre rests above (0, 0) of the slab at height `pose_y`: the height where its
/// overlap with the slab's spheres is a cap `SURFACE_CAP` × TIP high (worked out here with collette's
/// lens volume, by scanning down in 1 µm steps).
fn surface_y(pose_y: f32) -> f32 {
    let level = std::f32::consts::PI * (SURFACE_CAP * TIP).powi(2) * (3.0 * TIP - SURFACE_CAP * TIP) / 3.0;
    let slab = utils::slab();
    let overlap = |y: f32| -> f32 {
        let p = Vec3::new(0.0, y - pose_y, 0.0);
        slab.spheres().iter().map(|s| lens_volume(TIP, s.radius, p.distance(s.center))).sum()
    };
    (0..20_000).map(|i| 0.01 - i as f32 * 1e-6).find(|&y| overlap(y) > level).expect("the slab is below")
}

/// Lockstep proxy rendering of a Touch whose hand follows `keys` over the slab (top face at y = 0).
fn rig(keys: Vec<Keyframe>) -> Lockstep<SimDevice> {
    let device = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::Keyframes(keys));
    let material = Material { stiffness_n_per_m3: 3e7, damping_ns_per_m: 2.0, friction: MU, texture: None };
    // The tool's material is far stiffer, so the slab's decides (series combination).
    let tool = ToolSpec::new(utils::ball_tool(), Material { stiffness_n_per_m3: 3e12, ..material });
    let config = RigConfig {
        rendering: Rendering::Proxy,
        proxy: ProxyRendering { volume_per_depth_m2: 1e-5, damping_ns_per_m: 0.0, ..Default::default() },
        ..RigConfig::default()
    };
    let mut rig = Lockstep::new(device, tool, &config, 1, None).expect("rig");
    let slab =
        ObjectSpec { id: 1, tree: utils::slab(), pose: Pose::from_translation(Vec3::new(0.0, -0.01, 0.0)), material };
    rig.add_object(slab).expect("slab");
    rig
}

fn key(t_s: f64, x: f32, y: f32) -> Keyframe {
    Keyframe { t_s, pose: Pose::from_translation(Vec3::new(x, y, 0.0)) }
}

#[test]
fn a_point_pressed_into_a_slab_sinks_only_as_far_as_the_spring_allows() {
    let surface = surface_y(-0.01);
    assert!(surface > 0.0 && surface < TIP, "the tip rests just above the slab's top face: {surface}");
    // The hand aims 6 mm below the surface; its 200 N/m grip against the 300 N/m proxy spring settles
    // at 200 / 500 of that: 2.4 mm deep.
    let mut rig = rig(vec![key(0.0, 0.0, 0.01), key(1.0, 0.0, surface - 0.006)]);
    let mut deepest = 0.0f32;
    for i in 0..3000u64 {
        let out = rig.tick(i * 1000);
        let t = rig.telemetry();
        let depth = t.tool_pose.translation.y - t.device.pose.translation.y;
        deepest = deepest.max(depth);
        let sideways = out.force.x.hypot(out.force.z);
        assert!(
            out.force.y >= 0.0 && sideways <= 0.1 * out.force.y + 1e-3 && out.torque == Vec3::ZERO,
            "tick {i}: {out:?}"
        );
    }
    let t = rig.telemetry();
    let depth = t.tool_pose.translation.y - t.device.pose.translation.y;
    assert!((t.tool_pose.translation.y - surface).abs() < 2e-4, "the proxy rests on the surface: {:?}", t.tool_pose);
    assert!((depth - 0.0024).abs() < 0.0004, "settled {depth} m deep");
    assert!((t.output.force.y - K * depth).abs() < 0.02, "F = k d: {} N at {depth} m", t.output.force.y);
    // On the way in (the safety layer ramps the force up at first) it never sank far past that.
    assert!(deepest < 0.0024 * 1.5, "sank {deepest} m deep on the way");
}

#[test]
fn dragged_along_the_slab_the_point_slides_with_coulomb_friction() {
    let press = surface_y(-0.01) - 0.006;
    let mut rig = rig(vec![key(0.0, 0.0, 0.01), key(1.0, 0.0, press), key(2.0, 0.0, press), key(4.0, 0.03, press)]);
    let mut ratios = Vec::new();
    let mut proxy_x = Vec::new();
    for i in 0..4000u64 {
        let out = rig.tick(i * 1000);
        if i > 2500 && out.force.y > 0.1 {
            ratios.push(-out.force.x / out.force.y);
            proxy_x.push(rig.telemetry().tool_pose.translation.x);
        }
    }
    ratios.sort_by(f32::total_cmp);
    let median = ratios[ratios.len() / 2];
    assert!((median - MU).abs() < 0.1, "drag over push while sliding: median {median}");
    let moved = proxy_x.last().copied().unwrap_or(0.0) - proxy_x[0];
    assert!(moved > 0.005, "the proxy slid along the surface ({moved} m), not stuck");
}

/// Strongest push along a stroke that repeats with the hand's travel, over the mean push into the
/// surface: the largest Fourier amplitude of the along-stroke force (less its mean, the friction) at a
/// period from 1.5 to 10 mm, over the mean normal force. Samples are (x of the hand, force).
fn strongest_repeat(samples: &[(f32, Vec3)]) -> f32 {
    let mean_along = samples.iter().map(|s| s.1.x).sum::<f32>() / samples.len() as f32;
    let normal = samples.iter().map(|s| s.1.y).sum::<f32>() / samples.len() as f32;
    let amplitude = |period: f32| {
        let (mut c, mut s, mut travel) = (0.0f32, 0.0f32, 0.0f32);
        for w in samples.windows(2) {
            let dx = (w[1].0 - w[0].0).abs();
            let phase = std::f32::consts::TAU * w[1].0 / period;
            c += (w[1].1.x - mean_along) * phase.cos() * dx;
            s += (w[1].1.x - mean_along) * phase.sin() * dx;
            travel += dx;
        }
        2.0 * c.hypot(s) / travel.max(f32::MIN_POSITIVE)
    };
    (0..=34).map(|i| amplitude(0.0015 + i as f32 * 0.00025)).fold(0.0, f32::max) / normal.max(f32::MIN_POSITIVE)
}

/// A 4 cm stroke at 15 mm/s pressed ~1 N into the slab, with its surface grid or on its packing:
/// the strongest repeat, and the hand's x and force while it slid.
fn stroke_over_the_slab(grid: bool) -> (f32, Vec<(f32, Vec3)>) {
    let press = -0.002;
    let keys = vec![key(0.0, -0.02, 0.01), key(1.0, -0.02, press), key(1.5, -0.02, press), key(4.17, 0.02, press)];
    let mut rig = rig(keys);
    if grid {
        let (v, t) = collette::shape::box_buffers(Vec3::new(0.05, 0.01, 0.05));
        let mesh = collette::TriMesh::new(v, t).expect("box");
        let grid = collette::SignedDistanceGrid::new(&mesh, 64).expect("grid");
        rig.set_surface(1, Some(std::sync::Arc::new(grid))).expect("grid");
    }
    let mut samples = Vec::new();
    for i in 0..4200u64 {
        let out = rig.tick(i * 1000);
        if (1700..4100).contains(&i) && out.force.y > 0.1 {
            samples.push((rig.device().true_position().x, out.force));
        }
    }
    assert!(samples.len() > 2000, "the stroke stayed on the slab ({} ticks)", samples.len());
    (strongest_repeat(&samples), samples)
}

#[test]
fn a_stroke_over_a_grid_backed_slab_slides_on_its_true_surface_without_the_packings_bumps() {
    let (on_grid, samples) = stroke_over_the_slab(true);
    let (on_packing, _) = stroke_over_the_slab(false);
    eprintln!("strongest repeat along the stroke: {on_grid:.4} on the grid, {on_packing:.4} on the packing");
    assert!(on_grid <= 0.02, "the grid's smooth face repeats nothing: {on_grid}");
    assert!(on_packing > 2.0 * on_grid, "the packing's bumps repeat more: {on_packing} against {on_grid}");
    // Friction kept: the drag over the push is the slab's coefficient while it slides.
    let mut ratios: Vec<f32> = samples.iter().map(|s| -s.1.x / s.1.y).collect();
    ratios.sort_by(f32::total_cmp);
    let median = ratios[ratios.len() / 2];
    assert!((median - MU).abs() < 0.1, "drag over push on the grid: median {median}");
}

#[test]
fn a_tip_pressed_into_a_grid_backed_slab_rests_on_its_true_face() {
    // On the grid the tip's centre rests (1 - SURFACE_CAP) x its radius above the true top face (y = 0),
    // wherever the packing's spheres are.
    let rest = (1.0 - SURFACE_CAP) * TIP;
    let mut rig = rig(vec![key(0.0, 0.003, 0.01), key(1.0, 0.003, -0.003)]);
    let (v, t) = collette::shape::box_buffers(Vec3::new(0.05, 0.01, 0.05));
    let grid = collette::SignedDistanceGrid::new(&collette::TriMesh::new(v, t).expect("box"), 64).expect("grid");
    rig.set_surface(1, Some(std::sync::Arc::new(grid))).expect("grid");
    for i in 0..2500u64 {
        rig.tick(i * 1000);
    }
    let t = rig.telemetry();
    assert!((t.tool_pose.translation.y - rest).abs() < 5e-5, "the proxy on the true face: {:?}", t.tool_pose);
    let depth = rest - t.device.pose.translation.y;
    assert!((t.output.force.y - K * depth).abs() < 0.05, "F = k d: {} N at {depth} m", t.output.force.y);
    assert!(t.objects().first().is_some_and(|c| c.touching && c.id == 1), "the slab is touched: {:?}", t.objects());
}
