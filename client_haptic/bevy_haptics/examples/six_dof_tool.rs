//! The paper's 6-DOF rendering: a 2 cm gemstone (its inner spheres) against the bunny's, force *and*
//! torque from the overlap volume (Eq. 1, 2) through a virtual coupling, on a simulated Phantom Premium
//! 1.5 6-DOF. Pressing the gem's edge into the bunny's side twists it. `-- --headless --seconds 5`
//! presses it in off-centre and drags it along.

mod support;

use bevy::prelude::*;
use bevy_haptics::prelude::*;
use support::Run;

/// Where the simulated hand rests, device frame, m (beside the bunny's back, to its +x side).
const START: Vec3 = Vec3::new(0.06, 0.09, 0.0);

fn main() {
    let run = Run::from_args("six_dof_tool");
    let mut app = run.app();
    app.add_plugins(HapticsPlugins)
        .insert_resource(HapticDevice::simulated("premium", START))
        .add_systems(Startup, setup);
    if run.headless {
        app.add_systems(Update, press_and_drag);
    } else {
        app.add_systems(Startup, |mut commands: Commands| {
            support::camera(&mut commands, Vec3::new(0.15, 0.15, 0.25), Vec3::new(0.0, 0.05, 0.0))
        })
        .add_systems(Update, (support::keyboard_hand, support::mouse_hand, support::show_tool));
    }
    app.run();
}

fn setup(mut commands: Commands, mut trees: ResMut<Assets<SphereTree>>, assets: Res<AssetServer>) {
    // The gem: built here in a few milliseconds (300 spheres); a bigger tree belongs in an `.ist` file.
    match SphereTree::gem(0.02, 300) {
        Ok(gem) => {
            commands.spawn((HapticTool::new(trees.add(gem)), ForceComponent::rigid_tool()));
        }
        Err(e) => error!("no gem: {e}"),
    }
    let tree = support::bunny(&assets, 0.01, 3000);
    commands.spawn((
        HapticCollider::new(tree),
        ForceComponent { stiffness_n_per_m3: 2e8, damping_ns_per_m: 5.0, ..default() },
        Transform::default(),
    ));
}

/// Into the bunny's back, off its centre, then along it (headless).
fn press_and_drag(time: Res<Time<Real>>, hand: Option<ResMut<SimulatedHand>>, mut step: Local<u32>) {
    let Some(mut hand) = hand else { return };
    let t = support::elapsed(&time);
    let stops = [(0.5, Vec3::new(0.02, 0.06, 0.0)), (2.0, Vec3::new(0.02, 0.06, 0.03)), (3.5, START)];
    if let Some(&(at, to)) = stops.get(*step as usize)
        && t > at
    {
        hand.move_to(to, 1.0);
        *step += 1;
    }
}
