//! What every example shares: `--headless --seconds N` (no window; the simulated device follows the
//! example's scripted path; one JSON line of the loop's figures at the end), `--realtime-priority P`
//! (FIFO priority for the haptic and collision threads: needs the right to use it), or a window
//! (`--screenshot PNG`: save the window after 120 frames and quit; T cycles the trees' depth).
// Each example uses part of this module.
#![allow(dead_code)]

use std::time::Duration;

use bevy::app::ScheduleRunnerPlugin;
use bevy::prelude::*;
use bevy_haptics::prelude::*;

/// How the example runs.
#[derive(Resource, Clone, Copy, Debug)]
pub struct Run {
    /// The example's name.
    pub name: &'static str,
    /// No window.
    pub headless: bool,
    /// Stop after this long, s (`None`: when the window closes).
    pub seconds: Option<f32>,
    /// Save the window to this PNG after 120 frames, then quit.
    pub screenshot: Option<&'static str>,
    /// Real-time FIFO priority for the haptic thread (the collision thread gets one less), 1..=99.
    pub realtime_priority: Option<i32>,
}

impl Run {
    /// Reads the command line; a bad argument ends the program with one line saying what is accepted.
    pub fn from_args(name: &'static str) -> Self {
        let mut run = Self { name, headless: false, seconds: None, screenshot: None, realtime_priority: None };
        let mut args = std::env::args().skip(1);
        while let Some(arg) = args.next() {
            match arg.as_str() {
                "--headless" => run.headless = true,
                "--seconds" => match args.next().and_then(|s| s.parse::<f32>().ok()).filter(|s| *s > 0.0) {
                    Some(s) => run.seconds = Some(s),
                    None => fail("--seconds takes a positive number of seconds"),
                },
                "--screenshot" => match args.next() {
                    Some(path) => run.screenshot = Some(Box::leak(path.into_boxed_str())),
                    None => fail("--screenshot takes the path of a PNG to write"),
                },
                "--realtime-priority" => match args.next().and_then(|s| s.parse::<i32>().ok()) {
                    Some(p) if (1..=99).contains(&p) => run.realtime_priority = Some(p),
                    _ => fail("--realtime-priority takes a FIFO priority from 1 to 99"),
                },
                other => fail(&format!(
                    "unknown argument {other:?}: use [--headless] [--seconds N] [--screenshot PNG] \
                     [--realtime-priority 1-99]"
                )),
            }
        }
        if run.headless && run.seconds.is_none() {
            run.seconds = Some(5.0);
        }
        run
    }

    /// An app with a window (or none, headless), the assets of the repository, and the example's end.
    pub fn app(self) -> App {
        let assets =
            AssetPlugin { file_path: concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets").into(), ..default() };
        let mut app = App::new();
        if self.headless {
            let frame = Duration::from_secs_f64(1.0 / 60.0);
            // Warnings and errors to stderr (`RUST_LOG` to see more); stdout keeps the JSON line alone.
            let log = bevy::log::LogPlugin { level: bevy::log::Level::WARN, ..default() };
            app.add_plugins((MinimalPlugins.set(ScheduleRunnerPlugin::run_loop(frame)), assets, log))
                .init_asset::<Mesh>();
        } else {
            // Pipelines compiled before the first frame: on a software renderer (lavapipe) the first
            // frames are black otherwise.
            let render = bevy::render::RenderPlugin { synchronous_pipeline_compilation: true, ..default() };
            app.add_plugins((DefaultPlugins.set(assets).set(render), bevy_haptics::HapticsDebugPlugin))
                .insert_resource(bevy_haptics::HapticsDebugConfig { tree_depth: None, ..default() })
                .add_systems(Update, (screenshot, toggle_trees, paint));
        }
        app.insert_resource(self).init_resource::<Figures>().add_systems(Startup, realtime).add_systems(Update, end);
        app
    }
}

/// The colour an entity is drawn in (with a window; a headless app has no renderer to draw it).
#[derive(Component, Clone, Copy)]
pub struct Paint(pub Color);

/// Gives each newly painted entity its material (windowed).
fn paint(
    mut commands: Commands,
    mut materials: ResMut<Assets<StandardMaterial>>,
    painted: Query<(Entity, &Paint), Added<Paint>>,
) {
    for (entity, Paint(color)) in &painted {
        let look = materials.add(StandardMaterial { base_color: *color, ..default() });
        commands.entity(entity).insert(MeshMaterial3d(look));
    }
}

/// With a window: a camera looking at `target` from `eye`, the hand moved by the keyboard and the
/// mouse, the tool drawn as a ball.
pub fn windowed(app: &mut App, eye: Vec3, target: Vec3) {
    app.add_systems(Startup, move |mut commands: Commands| camera(&mut commands, eye, target))
        .add_systems(Update, (keyboard_hand, mouse_hand, show_tool));
}

/// Whether every collider's sphere tree is built (a `SphereTreeFromMesh` builds it on the async pool,
/// in a few tenths of a second): a scripted hand waits for it, so that it never reaches an object that
/// is not there yet on a slow machine.
pub fn colliders_ready(
    trees: &Assets<SphereTree>,
    colliders: &Query<&HapticCollider>,
    building: &Query<(), With<SphereTreeFromMesh>>,
) -> bool {
    building.is_empty() && colliders.iter().all(|c| trees.contains(&c.tree))
}

/// An example's own figures, added to its JSON line (e.g. how far a pushed box moved).
#[derive(Resource, Default)]
pub struct Figures(pub serde_json::Map<String, serde_json::Value>);

/// Gives the threads the real-time priority asked for (`Startup`: before they start in `PostStartup`).
fn realtime(run: Res<Run>, device: Option<ResMut<HapticDevice>>) {
    if let (Some(priority), Some(mut device)) = (run.realtime_priority, device) {
        device.realtime_priority = Some(priority);
    }
}

fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(2)
}

/// Seconds since the example started.
pub fn elapsed(time: &Time<Real>) -> f32 {
    time.elapsed_secs()
}

/// After `--seconds`, prints the loop's figures as one JSON line and exits.
fn end(
    run: Res<Run>,
    time: Res<Time<Real>>,
    stats: Res<HapticStats>,
    status: Res<HapticStatus>,
    figures: Res<Figures>,
    mut exit: MessageWriter<AppExit>,
) {
    let Some(seconds) = run.seconds else { return };
    if elapsed(&time) < seconds {
        return;
    }
    if let HapticStatus::Failed(why) = &*status {
        fail(&format!("haptics did not start: {why}"));
    }
    let mut line = serde_json::json!({
        "example": run.name,
        "seconds": seconds,
        "haptic_hz_min": stats.haptic.min_hz(),
        "collision_hz_min": stats.collision.min_hz(),
        "haptic_hz_p10": stats.haptic.quantile_hz(0.1),
        "haptic_hz_median": stats.haptic.quantile_hz(0.5),
        "collision_hz_p10": stats.collision.quantile_hz(0.1),
        "collision_hz_median": stats.collision.quantile_hz(0.5),
        "contacts": stats.contacts_started,
        "max_force_n": stats.max_force_n,
        "max_force_step_n": stats.max_force_step_n,
        "max_force_rate_n_per_s": stats.max_force_rate_n_per_s,
        "max_torque_nm": stats.max_torque_nm,
        "ticks": stats.ticks,
        "non_finite": stats.non_finite,
    });
    if let Some(line) = line.as_object_mut() {
        line.extend(figures.0.clone());
    }
    println!("{line}");
    exit.write(AppExit::Success);
}

/// Saves the window after 120 frames, then quits once the file is written (`--screenshot`).
fn screenshot(run: Res<Run>, mut commands: Commands, mut frames: Local<u32>, mut exit: MessageWriter<AppExit>) {
    use bevy::render::view::screenshot::{Screenshot, save_to_disk};
    let Some(path) = run.screenshot else { return };
    *frames += 1;
    if *frames == 120 {
        // An older picture at the path would end the wait before this one is written.
        let _ = std::fs::remove_file(path);
        commands.spawn(Screenshot::primary_window()).observe(save_to_disk(path));
    }
    if *frames > 125 && std::path::Path::new(path).exists() || *frames > 720 {
        exit.write(AppExit::Success);
    }
}

/// Moves the simulated hand with the mouse (windowed): dragging with the left button moves it in the
/// horizontal plane (a quarter of a millimetre a pixel, right and towards the viewer as the mouse goes
/// right and down), the wheel up and down (5 mm a line).
pub fn mouse_hand(
    buttons: Res<ButtonInput<MouseButton>>,
    motion: Res<bevy::input::mouse::AccumulatedMouseMotion>,
    scroll: Res<bevy::input::mouse::AccumulatedMouseScroll>,
    hand: Option<ResMut<SimulatedHand>>,
) {
    let Some(mut hand) = hand else { return };
    let drag = if buttons.pressed(MouseButton::Left) { motion.delta } else { Vec2::ZERO };
    let lines = match scroll.unit {
        bevy::input::mouse::MouseScrollUnit::Line => scroll.delta.y,
        bevy::input::mouse::MouseScrollUnit::Pixel => scroll.delta.y / 20.0,
    };
    let step = Vec3::new(drag.x * 0.000_25, lines * 0.005, drag.y * 0.000_25);
    if step != Vec3::ZERO {
        let at = hand.goal().sample(hand.now_us()).translation;
        hand.set(HandGoal::Hold(bevy_haptics::libs::haptic_common::Pose::from_translation(at + step)));
    }
}

/// Moves the simulated hand with the keyboard (windowed): arrows in the horizontal plane, PageUp and
/// PageDown up and down, 5 cm/s.
pub fn keyboard_hand(keys: Res<ButtonInput<KeyCode>>, hand: Option<ResMut<SimulatedHand>>, time: Res<Time>) {
    let Some(mut hand) = hand else { return };
    let pairs = [
        (KeyCode::ArrowLeft, Vec3::NEG_X),
        (KeyCode::ArrowRight, Vec3::X),
        (KeyCode::ArrowUp, Vec3::NEG_Z),
        (KeyCode::ArrowDown, Vec3::Z),
        (KeyCode::PageUp, Vec3::Y),
        (KeyCode::PageDown, Vec3::NEG_Y),
    ];
    let direction: Vec3 = pairs.iter().filter(|(k, _)| keys.pressed(*k)).map(|(_, d)| *d).sum();
    if direction != Vec3::ZERO {
        let now = hand.now_us();
        let at = hand.goal().sample(now).translation;
        hand.set(HandGoal::Hold(bevy_haptics::libs::haptic_common::Pose::from_translation(
            at + direction * 0.05 * time.delta_secs(),
        )));
    }
}

/// A camera looking at `target` from `eye`, and a light (windowed).
pub fn camera(commands: &mut Commands, eye: Vec3, target: Vec3) {
    commands.spawn((Camera3d::default(), Transform::from_translation(eye).looking_at(target, Vec3::Y)));
    // No shadows: their default bias is for scenes in metres, not a 10 cm bunny.
    let sun = DirectionalLight { illuminance: 12_000.0, shadow_maps_enabled: false, ..default() };
    commands.spawn((sun, Transform::from_xyz(1.0, 2.0, 1.5).looking_at(Vec3::ZERO, Vec3::Y)));
    let lamp = PointLight { intensity: 20_000.0, range: 3.0, shadow_maps_enabled: false, ..default() };
    commands.spawn((lamp, Transform::from_translation(eye + Vec3::Y * 0.2)));
    commands.insert_resource(GlobalAmbientLight { brightness: 80.0, ..default() });
    commands.insert_resource(ClearColor(Color::srgb(0.05, 0.06, 0.09)));
}

/// Shows the tool as a white ball on the tool entity (which follows the device); the debug plugin draws
/// the force (red) and torque (blue) arrows.
pub fn show_tool(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    tools: Query<(Entity, &HapticTool), Added<HapticTool>>,
) {
    for (tool, spec) in &tools {
        let white = materials.add(StandardMaterial { base_color: Color::WHITE, unlit: true, ..default() });
        commands.entity(tool).insert((Mesh3d(meshes.add(Sphere::new(spec.tip_radius_m))), MeshMaterial3d(white)));
    }
}

/// T shows the sphere trees one level deeper each time, then hides them (windowed).
fn toggle_trees(keys: Res<ButtonInput<KeyCode>>, mut config: ResMut<bevy_haptics::HapticsDebugConfig>) {
    if keys.just_pressed(KeyCode::KeyT) {
        config.tree_depth = match config.tree_depth {
            None => Some(0),
            Some(d) if d >= 6 => None,
            Some(d) => Some(d + 1),
        };
    }
}

/// The Stanford bunny's sphere tree, loaded from the repository's `assets/meshes/bunny.obj` (about 10
/// units tall) times `scale` (to metres), packed with `spheres` spheres on Bevy's asset threads.
pub fn bunny(assets: &AssetServer, scale: f32, spheres: usize) -> Handle<SphereTree> {
    assets
        .load_builder()
        .with_settings(move |s: &mut SphereTreeSettings| {
            s.scale = scale;
            s.spheres = spheres;
        })
        .load("meshes/bunny.obj")
}
