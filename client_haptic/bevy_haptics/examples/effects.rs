//! Force effects, each a `HapticEffect` on an entity: a spring to a point, a viscous pool, a vibrating
//! plate and a magnetic bunny (pulls the tip onto its surface), side by side along x; a simulated
//! 3D Systems Touch visits them. `-- --headless --seconds 7` follows the visit as a script.

mod support;

use bevy::prelude::*;
use bevy_haptics::prelude::*;
use support::Run;

/// Where each effect sits along x, m (at y = 0.03, z = 0).
const SPRING_X: f32 = -0.08;
const POOL_X: f32 = -0.03;
const PLATE_X: f32 = 0.02;
const BUNNY_X: f32 = 0.07;
const HEIGHT: f32 = 0.03;

fn main() {
    let run = Run::from_args("effects");
    let mut app = run.app();
    app.add_plugins(HapticsPlugins)
        .insert_resource(HapticDevice::simulated("touch", Vec3::new(SPRING_X, HEIGHT + 0.02, 0.0)))
        .add_systems(Startup, setup);
    if run.headless {
        app.add_systems(Update, visit);
    } else {
        app.add_systems(Startup, |mut commands: Commands| {
            support::camera(&mut commands, Vec3::new(0.0, 0.12, 0.25), Vec3::new(0.0, HEIGHT, 0.0))
        })
        .add_systems(Update, (support::keyboard_hand, support::mouse_hand, support::show_tool));
    }
    app.run();
}

fn setup(mut commands: Commands, assets: Res<AssetServer>) {
    commands.spawn(HapticTool::ball(0.003));
    let at = |x: f32| Transform::from_xyz(x, HEIGHT, 0.0);
    // A spring to a point, 2 cm around it.
    commands.spawn((
        HapticEffect { kind: EffectKind::Spring { stiffness_n_per_m: 150.0, damping_ns_per_m: 1.0 }, radius_m: 0.02 },
        at(SPRING_X),
    ));
    // A pool of honey.
    commands.spawn((HapticEffect { kind: EffectKind::Viscous { damping_ns_per_m: 8.0 }, radius_m: 0.02 }, at(POOL_X)));
    // A plate buzzing up and down at 60 Hz.
    commands.spawn((
        HapticEffect { kind: EffectKind::Vibration { amplitude_n: 0.4, frequency_hz: 60.0 }, radius_m: 0.02 },
        at(PLATE_X),
    ));
    // A 5 cm bunny that pulls the tip onto its surface from 1.5 cm away, and pushes back when touched.
    let tree = support::bunny(&assets, 0.005, 2000);
    commands.spawn((
        HapticCollider::new(tree),
        ForceComponent { stiffness_n_per_m3: 3e7, ..default() },
        HapticEffect { kind: EffectKind::Magnetic { strength_n: 0.8, reach_m: 0.015 }, radius_m: 0.0 },
        Transform::from_xyz(BUNNY_X, 0.0, 0.0),
    ));
}

/// Through the spring, the pool and the plate, then down onto the bunny (headless).
fn visit(time: Res<Time<Real>>, hand: Option<ResMut<SimulatedHand>>, mut step: Local<u32>) {
    let Some(mut hand) = hand else { return };
    let t = support::elapsed(&time);
    let stops = [
        (0.3, Vec3::new(SPRING_X + 0.01, HEIGHT, 0.0)),
        (1.5, Vec3::new(POOL_X, HEIGHT, 0.0)),
        (3.0, Vec3::new(PLATE_X, HEIGHT, 0.0)),
        (4.5, Vec3::new(BUNNY_X, 0.06, 0.0)),
        (5.5, Vec3::new(BUNNY_X, 0.01, 0.0)),
    ];
    if let Some(&(at, to)) = stops.get(*step as usize)
        && t > at
    {
        hand.move_to(to, 0.8);
        *step += 1;
    }
}
