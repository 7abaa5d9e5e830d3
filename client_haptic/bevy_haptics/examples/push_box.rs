//! Push a box across a table: the box is an avian3d rigid body (gravity, the table's friction) and a
//! `HapticPushable` of the same mass. The tool moves it on the haptic thread at once (the hand feels
//! its 200 g and the table's friction, not a wall), and each frame the impulses go to avian's body
//! (the `avian3d` feature), whose moves come back to the threads as any moved collider's.
//! `-- --headless --seconds 5` pushes it 6 cm along +x with the simulated hand and prints how far it
//! went.
//!
//! `cargo run -p bevy_haptics --features avian3d --example push_box`

mod support;

use avian3d::prelude::*;
use bevy::prelude::*;
use bevy_haptics::prelude::*;
use support::{Figures, Paint, Run, colliders_ready};

/// Where the simulated hand starts, device frame = world, m: left of the box, at its half height.
const START: Vec3 = Vec3::new(-0.06, 0.02, 0.0);
/// The box's side, m, and mass, kg.
const SIDE_M: f32 = 0.04;
const MASS_KG: f32 = 0.2;

/// The box.
#[derive(Component)]
struct PushedBox;

fn main() {
    let run = Run::from_args("push_box");
    let mut app = run.app();
    app.add_plugins((HapticsPlugins, PhysicsPlugins::default()))
        .insert_resource(HapticDevice::simulated("touch", START))
        .add_systems(Startup, setup)
        .add_systems(Update, report);
    if run.headless {
        app.add_systems(Update, push);
    } else {
        support::windowed(&mut app, Vec3::new(0.05, 0.12, 0.2), Vec3::ZERO);
    }
    app.run();
}

fn setup(mut commands: Commands, mut meshes: ResMut<Assets<Mesh>>) {
    commands.spawn(HapticTool::ball(0.005));
    // The table: avian's alone (the tool never reaches it).
    commands.spawn((
        RigidBody::Static,
        Collider::cuboid(0.4, 0.02, 0.4),
        Mesh3d(meshes.add(Cuboid::new(0.4, 0.02, 0.4))),
        Transform::from_xyz(0.0, -0.01, 0.0),
        Paint(Color::srgb(0.5, 0.35, 0.2)),
    ));
    // The box: avian's body and collider, and the haptic copy of the same mass with its tree built from
    // the same mesh.
    commands.spawn((
        PushedBox,
        RigidBody::Dynamic,
        Collider::cuboid(SIDE_M, SIDE_M, SIDE_M),
        Mass(MASS_KG),
        Friction::new(0.3),
        Mesh3d(meshes.add(Cuboid::new(SIDE_M, SIDE_M, SIDE_M))),
        SphereTreeFromMesh { spheres: 1000 },
        HapticPushable::new(MASS_KG),
        ForceComponent { stiffness_n_per_m3: 3e8, ..default() },
        Transform::from_xyz(0.0, SIDE_M / 2.0, 0.0),
        Paint(Color::srgb(0.8, 0.2, 0.2)),
    ));
}

/// Along +x through where the box stands, then back (headless), once the box's tree is built.
fn push(
    time: Res<Time<Real>>,
    hand: Option<ResMut<SimulatedHand>>,
    trees: Res<Assets<SphereTree>>,
    colliders: Query<&HapticCollider>,
    building: Query<(), With<SphereTreeFromMesh>>,
    mut start: Local<Option<f32>>,
    mut step: Local<u32>,
) {
    let Some(mut hand) = hand else { return };
    let now = support::elapsed(&time);
    if start.is_none() && colliders_ready(&trees, &colliders, &building) {
        *start = Some(now);
    }
    let Some(t) = start.map(|s| now - s) else { return };
    match *step {
        0 if t > 0.5 => hand.move_to(Vec3::new(0.04, START.y, 0.0), 1.5),
        1 if t > 2.3 => hand.move_to(START, 0.8),
        _ => return,
    }
    *step += 1;
}

/// How far the box went, and the pushes handed to avian.
fn report(
    boxes: Query<&Transform, With<PushedBox>>,
    mut pushed: MessageReader<ToolPushed>,
    mut figures: ResMut<Figures>,
    mut impulse: Local<Vec3>,
) {
    *impulse += pushed.read().map(|p| p.impulse_ns).sum::<Vec3>();
    let Some(t) = boxes.iter().next() else { return };
    figures.0.insert("box_moved_x_m".into(), t.translation.x.into());
    figures.0.insert("box_moved_z_m".into(), t.translation.z.into());
    figures.0.insert("box_height_m".into(), t.translation.y.into());
    figures.0.insert("impulse_x_ns".into(), impulse.x.into());
}
