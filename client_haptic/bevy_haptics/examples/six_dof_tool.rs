//! The paper's 6-DOF rendering: a 2 cm gemstone against the bunny, force *and* torque from the overlap
//! volume (Eq. 1, 2) through a virtual coupling, on a simulated Phantom Premium 1.5 6-DOF. Pressing the
//! gem's edge into the bunny's side twists it. Both trees come with their mesh's surface grid and shell,
//! so the overlap is measured from both surfaces (right at any depth, the bunny's thin ears included);
//! without them (`SphereTree::gem` alone, `support::bunny`'s default settings) it is the paper's inner
//! spheres. `-- --headless --seconds 5` presses it in off-centre and drags it along.

mod support;

use bevy::prelude::*;
use bevy_haptics::prelude::*;
use support::{Figures, Run};

/// Where the simulated hand rests, device frame, m (beside the bunny's back, to its +x side).
const START: Vec3 = Vec3::new(0.06, 0.09, 0.0);

fn main() {
    let run = Run::from_args("six_dof_tool");
    let mut app = run.app();
    app.add_plugins(HapticsPlugins)
        .insert_resource(HapticDevice::simulated("premium", START))
        .add_systems(Startup, setup);
    if run.headless {
        app.add_systems(Update, (press_and_drag, count_steps));
    } else {
        app.add_systems(Startup, |mut commands: Commands| {
            support::camera(&mut commands, Vec3::new(0.15, 0.15, 0.25), Vec3::new(0.0, 0.05, 0.0))
        })
        .add_systems(Update, (support::keyboard_hand, support::mouse_hand, support::show_tool));
    }
    app.run();
}

fn setup(mut commands: Commands, mut trees: ResMut<Assets<SphereTree>>, assets: Res<AssetServer>) {
    // The gem: built here in a few milliseconds (300 spheres; its grid and shell in a few more); a bigger
    // tree belongs in an `.ist` file.
    let mesh = bevy_haptics::libs::collette::scene::brilliant_cut(0.02);
    match SphereTree::gem(0.02, 300).and_then(|gem| gem.with_surfaces_of(&mesh, 64, 0.001)) {
        Ok(gem) => {
            commands.spawn((HapticTool::new(trees.add(gem)), ForceComponent::rigid_tool()));
        }
        Err(e) => error!("no gem: {e}"),
    }
    // The bunny's grid (128 voxels) and shell (1.5 mm edges) are built with its tree on the asset threads.
    let tree = assets
        .load_builder()
        .with_settings(|s: &mut SphereTreeSettings| {
            *s = SphereTreeSettings { spheres: 3000, scale: 0.01, surface_voxels: 128, shell_edge_m: 0.0015 }
        })
        .load("meshes/bunny.obj");
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

/// Counts the collision steps in contact, those that measured the whole overlap from both surfaces (one
/// contact), and those whose budget ran out (headless).
fn count_steps(frame: Res<HapticFrame>, mut figures: ResMut<Figures>, mut counts: Local<[u64; 3]>) {
    for step in frame.steps.iter().filter(|s| s.contacts > 0) {
        counts[0] += 1;
        counts[1] += u64::from(step.contacts == 1);
        counts[2] += u64::from(step.budget_hit);
    }
    for (key, count) in ["steps_in_contact", "steps_one_contact", "steps_cut_short"].into_iter().zip(*counts) {
        figures.0.insert(key.into(), count.into());
    }
}
