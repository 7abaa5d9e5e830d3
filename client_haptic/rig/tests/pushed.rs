//! Objects the tool pushes: the simulated hand pushes a box the "game" simulates at 60 Hz (a box on a
//! table with friction, a wall), the rig hands back impulses, the game applies them and sends its poses
//! with their times. The box moves the way it is pushed, the impulses are the opposite of what the tool
//! felt, and the loop stays passive: the energy in the game's box never exceeds the work the hand did
//! through the device, and nothing buzzes once the hand holds still.

mod utils;

use std::sync::{Arc, OnceLock};

use collette::shape::box_buffers;
use collette::{BuildOptions, InnerSphereTree, TriMesh};
use forcecomp::{Material, SafetyConfig};
use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectPush, ObjectSpec, PushCoupling, Rendering, RigConfig, ToolSpec};
use haptico::presets;
use haptico::sim::{Keyframe, SimConfig, SimDevice, TargetPath};

/// A 60 Hz game's frame period, µs.
const FRAME_US: u64 = 16_667;
const G: f32 = 9.81;

/// A 4 cm cube.
fn cube() -> Arc<InnerSphereTree> {
    static T: OnceLock<Arc<InnerSphereTree>> = OnceLock::new();
    T.get_or_init(|| {
        let (v, t) = box_buffers(Vec3::splat(0.02));
        let mesh = TriMesh::new(v, t).expect("box mesh");
        Arc::new(collette::build(&mesh, &BuildOptions::spheres(1000), &mut |_| {}).expect("tree").0)
    })
    .clone()
}

/// The game's side: a box sliding on a table (Coulomb friction `mu`), stopped by a wall at
/// `wall_x` (its centre cannot pass it; the same friction there), moved by the impulses the rig hands
/// back.
struct GameBox {
    mass_kg: f32,
    mu: f32,
    wall_x: f32,
    position: Vec3,
    velocity: Vec3,
    /// The impulses handed back, summed, N·s, and the angular ones, N·m·s.
    impulse: Vec3,
    angular_impulse: Vec3,
}

impl GameBox {
    /// One frame of `dt` seconds with the pushes taken from the rig.
    fn frame(&mut self, pushes: &[ObjectPush], dt: f32) {
        let push = pushes.iter().find(|p| p.id == 1);
        let impulse = push.map_or(Vec3::ZERO, |p| p.impulse_ns);
        self.impulse += impulse;
        self.angular_impulse += push.map_or(Vec3::ZERO, |p| p.angular_impulse_nms);
        // The table holds it up and rubs: only x and z move.
        let mut v = self.velocity + Vec3::new(impulse.x, 0.0, impulse.z) / self.mass_kg;
        let rub = self.mu * G * dt;
        v = if v.length() <= rub { Vec3::ZERO } else { v - v.normalize() * rub };
        self.position += v * dt;
        if self.position.x > self.wall_x {
            self.position -= v * dt;
            // The wall takes the push along x and rubs what is left along z.
            let rub = self.mu * v.x.max(0.0);
            v.z = if v.z.abs() <= rub { 0.0 } else { v.z - v.z.signum() * rub };
            v.x = 0.0;
            self.position += v * dt;
            self.position.x = self.wall_x;
        }
        self.velocity = v;
    }

    fn kinetic_energy_j(&self) -> f32 {
        0.5 * self.mass_kg * self.velocity.length_squared()
    }
}

/// What a run shows.
struct Run {
    /// The game's box at the end.
    game: GameBox,
    /// Most energy the game's box had above the work the hand had done through the device so far, J,
    /// and that work at the end.
    worst_excess_j: f32,
    work_j: f32,
    /// The contact impulse on the tool over the run, N·s.
    tool_impulse: Vec3,
    /// Largest kinetic energy of the device in the last `quiet_s` seconds, J, and the device force's
    /// spread (max - min of its length) there, N; its last force, N.
    quiet_ke_j: f32,
    quiet_force_spread_n: f32,
    last_force_n: f32,
}

/// The hand moves along `path` (device frame = scene) holding a 5 mm ball; the box (`mass_kg`) starts
/// with its centre at (0.03, 0, z_box). Runs `seconds`, the last `quiet_s` with the hand still.
fn push(mass_kg: f32, mu: f32, wall_x: f32, z_box: f32, path: Vec<Keyframe>, seconds: f64, quiet_s: f64) -> Run {
    push_with(PushCoupling::default(), mass_kg, mu, wall_x, z_box, path, seconds, quiet_s)
}

#[allow(clippy::too_many_arguments)]
fn push_with(
    coupling: PushCoupling,
    mass_kg: f32,
    mu: f32,
    wall_x: f32,
    z_box: f32,
    path: Vec<Keyframe>,
    seconds: f64,
    quiet_s: f64,
) -> Run {
    let mut device_config = SimConfig::new(presets::touch());
    device_config.encoder_resolution_m = 0.0;
    let device = SimDevice::new(device_config, TargetPath::Keyframes(path));
    let config = RigConfig {
        rendering: Rendering::Coupled,
        safety: Some(SafetyConfig { ramp_in_s: 0.05, ..SafetyConfig::for_limits(3.3, 0.0) }),
        pushes: coupling,
        ..RigConfig::default()
    };
    // Stiff, as the coupling's own energy test (tests/passivity.rs): the hardest case for passivity.
    let stiff = Material { stiffness_n_per_m3: 1e9, damping_ns_per_m: 1.0, friction: 0.0, texture: None };
    let tool = ToolSpec::new(utils::ball_tool(), stiff);
    let mut rig = Lockstep::new(device, tool, &config, 1, None).expect("rig");
    let start = Vec3::new(0.03, 0.0, z_box);
    let spec = ObjectSpec { id: 1, tree: cube(), pose: Pose::from_translation(start), material: stiff };
    rig.add_pushable(spec, mass_kg).expect("pushable");
    let mut game = GameBox {
        mass_kg,
        mu,
        wall_x,
        position: start,
        velocity: Vec3::ZERO,
        impulse: Vec3::ZERO,
        angular_impulse: Vec3::ZERO,
    };
    let (mut pushes, mut samples) = (Vec::new(), Vec::new());
    let (mut work, mut worst_excess, mut tool_impulse) = (0.0f32, f32::NEG_INFINITY, Vec3::ZERO);
    let (mut quiet_ke, mut quiet_min, mut quiet_max, mut last_force) = (0.0f32, f32::INFINITY, 0.0f32, 0.0);
    let ticks = (seconds * 1000.0) as u64;
    let quiet_from = ticks - (quiet_s * 1000.0) as u64;
    let mut last_frame = 0;
    for i in 0..ticks {
        let t_us = i * 1000;
        if t_us >= last_frame + FRAME_US {
            pushes.clear();
            rig.take_pushes(&mut pushes);
            game.frame(&pushes, (t_us - last_frame) as f32 * 1e-6);
            last_frame = t_us;
            rig.set_object_pose_at(1, Pose::from_translation(game.position), t_us).expect("pose");
        }
        let out = rig.tick(t_us);
        let v = rig.device().true_velocity();
        // The hand's work into the scene: against the force the device pushes back with.
        work += -out.force.dot(v) * 1e-3;
        worst_excess = worst_excess.max(game.kinetic_energy_j() - work);
        rig.drain_force_samples(&mut samples);
        for s in samples.drain(..) {
            tool_impulse += s.contact_force * 1e-3;
        }
        if i >= quiet_from {
            let f = out.force.length();
            quiet_ke = quiet_ke.max(rig.device().kinetic_energy_j());
            (quiet_min, quiet_max, last_force) = (quiet_min.min(f), quiet_max.max(f), f);
        }
    }
    Run {
        game,
        worst_excess_j: worst_excess,
        work_j: work,
        tool_impulse,
        quiet_ke_j: quiet_ke,
        quiet_force_spread_n: quiet_max - quiet_min,
        last_force_n: last_force,
    }
}

fn key(t_s: f64, x: f32, z: f32) -> Keyframe {
    Keyframe { t_s, pose: Pose::from_translation(Vec3::new(x, 0.0, z)) }
}

/// No energy from nowhere, and no buzz once the hand is still.
fn assert_passive(run: &Run, what: &str) {
    eprintln!(
        "{what}: work {:.2e} J, worst excess {:.2e} J, quiet KE {:.2e} J, force spread {:.3} N, last force {:.3} N, \
         box at {:?}",
        run.work_j, run.worst_excess_j, run.quiet_ke_j, run.quiet_force_spread_n, run.last_force_n, run.game.position
    );
    assert!(run.worst_excess_j <= 1e-6, "{what}: the box gained more than the hand gave: {:e} J", run.worst_excess_j);
    assert!(run.quiet_ke_j < 1e-6, "{what}: the device still moves with the hand still: {:e} J", run.quiet_ke_j);
    assert!(run.quiet_force_spread_n < 0.05, "{what}: the force buzzes: {} N of spread", run.quiet_force_spread_n);
}

#[test]
fn a_light_box_pushed_along_the_table_moves_the_way_it_is_pushed_and_gains_only_what_the_hand_gave() {
    // 50 g; the hand goes 6 cm along +x at 0.1 m/s (the ball meets the box's face after 5 mm), then back.
    let path = vec![key(0.0, 0.0, 0.0), key(0.6, 0.06, 0.0), key(0.9, 0.0, 0.0)];
    let run = push(0.05, 0.3, 1.0, 0.0, path, 2.5, 1.0);
    assert_passive(&run, "50 g pushed and released");
    let moved = run.game.position - Vec3::new(0.03, 0.0, 0.0);
    assert!((0.04..0.07).contains(&moved.x), "pushed about 5.5 cm along +x: {moved:?}");
    assert!(moved.z.abs() < 0.003, "straight: {moved:?}");
    assert_eq!(run.game.velocity, Vec3::ZERO, "the table stopped it");
    // Equal and opposite: what the game received is what the tool felt, reversed.
    let sum = run.game.impulse + run.tool_impulse;
    assert!(
        sum.length() <= 0.05 * run.tool_impulse.length(),
        "handed {:?} N·s against the tool's {:?} N·s",
        run.game.impulse,
        run.tool_impulse
    );
}

/// The hand pushes 6 cm along +x at 0.1 m/s and lets go: the 50 g box on ice slides on.
fn on_ice(coupling: PushCoupling) -> Run {
    let path = vec![key(0.0, 0.0, 0.0), key(0.6, 0.06, 0.0), key(0.9, 0.0, 0.0)];
    push_with(coupling, 0.05, 0.0, 1.0, 0.0, path, 2.5, 1.0)
}

#[test]
fn a_light_box_pushed_and_released_on_ice_leaves_no_faster_than_a_hit_could_send_it() {
    let run = on_ice(PushCoupling::default());
    assert_passive(&run, "50 g pushed and released on ice");
    let v = run.game.velocity;
    eprintln!("on ice: leaves at {v:?} m/s");
    // Struck elastically by the 150 g hand at 0.1 m/s, a 50 g box leaves at 0.15 m/s; nothing faster.
    assert!(v.x > 0.05 && v.length() <= 0.15 * 1.1, "it slides on along +x, no faster than a hit sends it: {v:?}");
}

#[test]
fn a_coupling_too_stiff_for_the_games_latency_gains_energy() {
    // The same push with the spring tuned for an 8 ms game (five times stiffer in frequency): the game's
    // late answer pumps energy into the box, which the energy check sees.
    let run = on_ice(PushCoupling { latency_s: 0.008 });
    eprintln!("too stiff: worst excess {:e} J", run.worst_excess_j);
    assert!(run.worst_excess_j > 1e-3, "the instability shows: {:e} J", run.worst_excess_j);
}

#[test]
fn a_box_pushed_off_its_centre_is_given_the_torque_that_turns_it() {
    // The ball meets the face 1.5 cm to the +z side of its centre: pushing +x there turns the box about +y.
    let path = vec![key(0.0, 0.0, 0.015), key(0.3, 0.03, 0.015), key(0.5, 0.0, 0.015)];
    let run = push(0.05, 0.3, 1.0, 0.0, path, 1.5, 0.5);
    let (l, a) = (run.game.impulse, run.game.angular_impulse);
    eprintln!("off centre: impulse {l:?} N·s, angular {a:?} N·m·s");
    assert!(l.x > 0.0, "pushed along +x: {l:?}");
    // About 1.5 cm times the push, about +y.
    let lever = a.y / l.x;
    assert!((0.010..0.020).contains(&lever), "turned about +y with a 1.5 cm lever: {lever} m ({a:?})");
    assert!(a.x.abs() + a.z.abs() < 0.2 * a.y, "about y only: {a:?}");
}

#[test]
fn a_heavy_box_leaned_on_holds_still_and_pushes_back_without_buzz() {
    // 5 kg on a table whose friction (24.5 N) no hand on a 3.3 N device overcomes: the hand presses 1 cm
    // into its face and holds.
    let path = vec![key(0.0, 0.0, 0.0), key(0.3, 0.02, 0.0)];
    let run = push(5.0, 0.5, 1.0, 0.0, path, 3.0, 1.0);
    assert_passive(&run, "5 kg leaned on");
    let moved = (run.game.position - Vec3::new(0.03, 0.0, 0.0)).length();
    assert!(moved < 1e-4, "it does not move: {moved} m");
    assert!(run.last_force_n > 0.5, "it pushes back: {} N", run.last_force_n);
}

#[test]
fn a_box_pinned_between_the_tool_and_a_wall_stays_calm() {
    // 200 g against a wall right behind it; the hand presses 1.5 cm into its face and holds.
    let path = vec![key(0.0, 0.0, 0.0), key(0.3, 0.02, 0.0)];
    let run = push(0.2, 0.3, 0.03, 0.0, path, 3.0, 1.0);
    assert_passive(&run, "200 g pinned");
    assert!(run.game.position.x <= 0.03, "the wall holds it: {:?}", run.game.position);
    assert_eq!(run.game.velocity, Vec3::ZERO, "at rest");
    assert!(run.game.position.z.abs() < 0.002, "it does not slip along the wall: {:?}", run.game.position);
    assert!(run.last_force_n > 0.5, "the wall is felt through the box: {} N", run.last_force_n);
}

#[test]
fn a_pushable_needs_a_positive_mass() {
    let (device, _) = haptico::mock::MockDevice::touch();
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let mut rig = Lockstep::new(device, tool, &RigConfig::default(), 1, None).expect("rig");
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let spec = ObjectSpec { id: 7, tree: cube(), pose: Pose::IDENTITY, material: Material::default() };
        let err = rig.add_pushable(spec, bad).expect_err("refused").to_string();
        assert!(err.contains("object 7") && err.contains("mass"), "{err}");
    }
}
