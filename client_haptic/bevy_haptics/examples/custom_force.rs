//! Your own force instead of ForceComp's: `HapticoPlugin` and `CollettePlugin` only, and a force
//! delegate bound to the haptic thread (the paper's ForceOnHapticTick) that renders a soft floor at the
//! device's y = 0. Collette still reports contacts with the slab that stands for the floor, so the game
//! hears about them. `-- --headless --seconds 3` presses the simulated hand into the floor and back.

mod support;

use bevy::prelude::*;
use bevy_haptics::prelude::*;
use support::Run;

/// Where the simulated hand rests, device frame, m.
const START: Vec3 = Vec3::new(0.0, 0.03, 0.0);
/// The floor's stiffness, N/m.
const FLOOR_N_PER_M: f32 = 300.0;

fn main() {
    let run = Run::from_args("custom_force");
    let mut app = run.app();
    app.add_plugins((HapticoPlugin, CollettePlugin::default()))
        .insert_resource(HapticDevice::simulated("touch", START))
        .add_systems(Startup, setup);
    // Runs on the haptic thread, 1000 times a second: no allocation, no lock, no log.
    app.world_mut().resource_mut::<HapticDelegates>().force_on_haptic_tick(|tick: &ForceOnHapticTick| {
        let y = tick.device.pose.translation.y;
        if y < 0.0 {
            let push = Vec3::Y * (-FLOOR_N_PER_M * y) - tick.device.linear_velocity.y * Vec3::Y * 1.0;
            tick.add(ForceTorque { force: push.max(Vec3::ZERO), torque: Vec3::ZERO });
        }
    });
    if run.headless {
        app.add_systems(Update, press);
    } else {
        support::windowed(&mut app, Vec3::new(0.1, 0.08, 0.15), Vec3::ZERO);
    }
    app.add_observer(|c: On<ContactStarted>| info!("the tool reached the floor ({} sphere pairs)", c.contact.pairs));
    app.run();
}

fn setup(mut commands: Commands, mut meshes: ResMut<Assets<Mesh>>) {
    commands.spawn(HapticTool::ball(0.003));
    // The slab under the floor: its sphere tree built from a Bevy mesh on the async compute pool.
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(0.2, 0.02, 0.2))),
        SphereTreeFromMesh { spheres: 500 },
        Transform::from_xyz(0.0, -0.01, 0.0),
    ));
}

/// Down 1 cm into the floor, hold, back up (headless).
fn press(time: Res<Time<Real>>, hand: Option<ResMut<SimulatedHand>>, mut step: Local<u32>) {
    let Some(mut hand) = hand else { return };
    let t = support::elapsed(&time);
    match *step {
        0 if t > 0.5 => hand.move_to(Vec3::new(0.0, -0.01, 0.0), 0.8),
        1 if t > 2.0 => hand.move_to(START, 0.5),
        _ => return,
    }
    *step += 1;
}
