//! Feel the Stanford bunny with a simulated Phantom Desktop (3-DOF: the tip is held on the surface by a
//! proxy). With a window, move the hand with the arrows and PageUp / PageDown, or drag it with the left
//! mouse button (the wheel moves it up and down); the red line is the force on the device.
//! `-- --headless --seconds 5` follows a scripted stroke over the bunny's back instead.

mod support;

use bevy::prelude::*;
use bevy_haptics::prelude::*;
use support::Run;

/// Where the simulated hand rests, device frame, m (13 cm above the floor, over the bunny's back).
const START: Vec3 = Vec3::new(0.0, 0.08, 0.0);

fn main() {
    let run = Run::from_args("touch_bunny");
    let mut app = run.app();
    app.add_plugins(HapticsPlugins)
        .insert_resource(HapticDevice {
            // The device's origin 5 cm above the bunny's feet.
            origin: Transform::from_xyz(0.0, 0.05, 0.0),
            ..HapticDevice::simulated("phantom desktop", START)
        })
        .add_systems(Startup, setup);
    if run.headless || run.screenshot.is_some() {
        app.add_systems(Update, stroke);
    }
    if !run.headless {
        app.add_systems(Startup, scenery)
            .add_systems(Update, (support::keyboard_hand, support::mouse_hand, support::show_tool));
    }
    app.run();
}

fn setup(mut commands: Commands, assets: Res<AssetServer>) {
    commands.spawn((HapticTool::ball(0.003), Name::new("tool")));
    // The bunny, 10 cm tall, its sphere tree built from the mesh on Bevy's asset threads.
    let tree = support::bunny(&assets, 0.01, 3000);
    commands.spawn((
        HapticCollider::new(tree),
        ForceComponent { stiffness_n_per_m3: 3e7, ..default() },
        Transform::default(),
        Name::new("bunny"),
    ));
}

/// Down onto the bunny's back, a circle on it, then up (headless; for a screenshot it stays on the back).
fn stroke(run: Res<Run>, time: Res<Time<Real>>, hand: Option<ResMut<SimulatedHand>>, mut step: Local<u32>) {
    let Some(mut hand) = hand else { return };
    let t = support::elapsed(&time);
    let start_us = hand.now_us();
    match *step {
        0 if t > 0.5 => hand.move_to(Vec3::new(0.0, -0.01, 0.0), 1.0),
        1 if t > 1.8 => hand.set(HandGoal::Orbit {
            centre: Vec3::new(0.0, -0.01, 0.0),
            radius: 0.015,
            start_rad: 0.0,
            period_s: 2.0,
            turns: 1.0,
            start_us,
        }),
        2 if t > 4.0 && run.headless => hand.move_to(START, 0.5),
        _ => return,
    }
    *step += 1;
}

/// The bunny to look at, a camera and a light (windowed).
fn scenery(mut commands: Commands, mut meshes: ResMut<Assets<Mesh>>, mut materials: ResMut<Assets<StandardMaterial>>) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/meshes/bunny.obj");
    match bevy_haptics::libs::collette::TriMesh::from_obj(path) {
        Ok(bunny) => {
            let positions: Vec<[f32; 3]> = bunny.vertices().iter().map(|v| (*v * 0.01).to_array()).collect();
            // The file winds its triangles clockwise seen from outside: reversed, the normals point out.
            let indices = bunny.triangles().iter().flat_map(|t| [t[0], t[2], t[1]]).collect();
            let mut mesh = Mesh::new(bevy::mesh::PrimitiveTopology::TriangleList, default())
                .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
                .with_inserted_indices(bevy::mesh::Indices::U32(indices));
            mesh.duplicate_vertices();
            mesh.compute_flat_normals();
            let look = materials.add(StandardMaterial { base_color: Color::srgb(0.8, 0.7, 0.6), ..default() });
            commands.spawn((Mesh3d(meshes.add(mesh)), MeshMaterial3d(look)));
        }
        Err(e) => error!("no bunny to show: {e}"),
    }
    support::camera(&mut commands, Vec3::new(0.08, 0.12, 0.15), Vec3::new(0.0, 0.05, 0.0));
}
