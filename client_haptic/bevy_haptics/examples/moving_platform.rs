//! An object the game moves: a platform sliding back and forth under the tool at 60 frames a second.
//! Its `Transform` is all the game changes; each frame's pose reaches the haptic threads with its time,
//! and they move the platform smoothly between frames (1 kHz) and feel its speed, so resting on it feels
//! like riding it, not a step each frame. `-- --headless --seconds 5` lowers the simulated hand onto
//! the platform and holds it there while it slides.

mod support;

use bevy::prelude::*;
use bevy_haptics::prelude::*;
use support::{Figures, Paint, Run, colliders_ready};

/// Where the simulated hand rests, device frame, m.
const START: Vec3 = Vec3::new(0.0, 0.03, 0.0);
/// The platform's travel either side of the centre, m, and its period, s.
const TRAVEL_M: f32 = 0.03;
const PERIOD_S: f32 = 2.0;

/// The platform.
#[derive(Component)]
struct Platform;

fn main() {
    let run = Run::from_args("moving_platform");
    let mut app = run.app();
    app.add_plugins(HapticsPlugins)
        .insert_resource(HapticDevice::simulated("touch", START))
        .add_systems(Startup, setup)
        .add_systems(Update, (slide, ride));
    if run.headless {
        app.add_systems(Update, lower);
    } else {
        support::windowed(&mut app, Vec3::new(0.1, 0.08, 0.15), Vec3::ZERO);
    }
    app.run();
}

fn setup(mut commands: Commands, mut meshes: ResMut<Assets<Mesh>>) {
    commands.spawn(HapticTool::ball(0.004));
    // A 10 x 2 x 6 cm platform whose top is at y = 0; its tree built from the mesh.
    commands.spawn((
        Platform,
        Mesh3d(meshes.add(Cuboid::new(0.1, 0.02, 0.06))),
        SphereTreeFromMesh { spheres: 1500 },
        ForceComponent { stiffness_n_per_m3: 3e7, ..default() },
        Transform::from_xyz(0.0, -0.01, 0.0),
        Paint(Color::srgb(0.3, 0.5, 0.7)),
    ));
}

/// The game moves the platform: a sine along x, once a frame.
fn slide(time: Res<Time<Real>>, mut platforms: Query<&mut Transform, With<Platform>>) {
    let x = TRAVEL_M * (std::f32::consts::TAU * support::elapsed(&time) / PERIOD_S).sin();
    for mut t in &mut platforms {
        t.translation.x = x;
    }
}

/// Counts the frames the tool rides the platform (its contact goes on while the platform moves).
fn ride(mut ongoing: MessageReader<ContactOngoing>, mut figures: ResMut<Figures>, mut frames: Local<u64>) {
    *frames += ongoing.read().count() as u64;
    figures.0.insert("frames_on_platform".into(), (*frames).into());
}

/// Down onto the platform and held there (headless), once its tree is built.
fn lower(
    hand: Option<ResMut<SimulatedHand>>,
    trees: Res<Assets<SphereTree>>,
    colliders: Query<&HapticCollider>,
    building: Query<(), With<SphereTreeFromMesh>>,
    mut done: Local<bool>,
) {
    let Some(mut hand) = hand else { return };
    if !*done && colliders_ready(&trees, &colliders, &building) {
        hand.move_to(Vec3::new(0.0, -0.004, 0.0), 0.5);
        *done = true;
    }
}
