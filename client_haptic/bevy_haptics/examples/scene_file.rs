//! The whole haptic set-up from a scene file, no set-up code: `assets/scenes/touch_bunny.scn.ron` holds
//! the tool and the bunny (its tree from `meshes/bunny.obj` through a `SphereTreeSource`, its
//! `ForceComponent`, its `Transform`); this program only loads it. With a window, the bunny is drawn as
//! its sphere tree (T changes the depth) and the arrows and PageUp / PageDown move the hand;
//! `-- --headless --seconds 5` strokes the bunny's back on a scripted path.

mod support;

use bevy::prelude::*;
use bevy::world_serialization::{DynamicWorldRoot, WorldSerializationPlugin};
use bevy_haptics::prelude::*;
use support::Run;

/// The bunny's back, world frame, m (the scene puts its feet 13 cm below the device's origin).
const BACK: Vec3 = Vec3::new(0.0, -0.09, 0.0);

fn main() {
    let run = Run::from_args("scene_file");
    let mut app = run.app();
    if run.headless {
        // The window's `DefaultPlugins` bring it; a headless app adds it.
        app.add_plugins(WorldSerializationPlugin);
    }
    // Bevy registers its own types by itself with its default `reflect_auto_register` feature; this
    // workspace builds Bevy without default features, so the one Bevy type the scene names is
    // registered here (bevy_haptics' plugins register theirs).
    app.register_type::<Transform>();
    app.add_plugins(HapticsPlugins).add_systems(Startup, load_scene);
    if run.headless || run.screenshot.is_some() {
        app.add_systems(Update, stroke);
    }
    if !run.headless {
        app.insert_resource(bevy_haptics::HapticsDebugConfig { tree_depth: Some(3), ..default() })
            .add_systems(Startup, |mut commands: Commands| {
                support::camera(&mut commands, Vec3::new(0.08, -0.01, 0.15), Vec3::new(0.0, -0.08, 0.0));
            })
            .add_systems(Update, (support::keyboard_hand, support::mouse_hand, support::show_tool));
    }
    app.run();
}

fn load_scene(mut commands: Commands, assets: Res<AssetServer>) {
    commands.spawn(DynamicWorldRoot(assets.load("scenes/touch_bunny.scn.ron")));
}

/// Down onto the bunny's back, a circle on it, then up (headless; for a screenshot it stays on the back).
fn stroke(run: Res<Run>, time: Res<Time<Real>>, hand: Option<ResMut<SimulatedHand>>, mut step: Local<u32>) {
    let Some(mut hand) = hand else { return };
    let t = support::elapsed(&time);
    let start_us = hand.now_us();
    match *step {
        0 if t > 0.5 => hand.move_to(BACK, 1.0),
        1 if t > 1.8 => hand.set(HandGoal::Orbit {
            centre: BACK,
            radius: 0.015,
            start_rad: 0.0,
            period_s: 2.0,
            turns: 1.0,
            start_us,
        }),
        2 if t > 4.0 && run.headless => hand.move_to(Vec3::ZERO, 0.5),
        _ => return,
    }
    *step += 1;
}
