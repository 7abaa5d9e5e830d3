//! The optional spectator window for sighted onlookers: the copy on the workbench, the stylus's
//! gemstone where the haptic loop has it, and the force on the device as an arrow.
//!
//! You need this module only with a window (feature `spectator`, no `--headless`). It reads what the
//! rest of the client already has ([`BenchView`]; the gemstone is `bevy_haptics`' tool entity, which
//! follows the device by itself) and draws the force with `bevy_haptics`' debug plugin; it never feeds
//! back into play.
//! [`ShotRequest`] saves one screenshot and quits (used for the README's picture and its test).

use std::path::PathBuf;

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::render::view::screenshot::{Screenshot, save_to_disk};
use bevy::window::{PresentMode, WindowResolution};

use bevy_haptics::{HapticTool, HapticsDebugConfig, HapticsDebugPlugin};

use crate::client::BenchView;
use crate::haptics::TOOL_DIAMETER_M;

/// Adds Bevy's default plugins with a small window and synchronous pipeline compilation (so the first
/// frames are not black on software renderers such as lavapipe).
pub fn add_window_plugins(app: &mut App) {
    app.add_plugins(
        DefaultPlugins
            .set(WindowPlugin {
                primary_window: Some(Window {
                    title: "Phantom Heist — Phantom's workbench".into(),
                    resolution: WindowResolution::new(640, 480),
                    present_mode: PresentMode::AutoVsync,
                    ..default()
                }),
                ..default()
            })
            .set(RenderPlugin { synchronous_pipeline_compilation: true, ..default() }),
    );
}

/// Save a screenshot to `path` after `after_frames` frames, then quit.
#[derive(Resource, Clone, Debug)]
pub struct ShotRequest {
    /// Where the PNG goes.
    pub path: PathBuf,
    /// Frames to wait (lavapipe needs ~120 before the first correct image).
    pub after_frames: u32,
}

/// The spectator's scene.
pub struct SpectatorPlugin;

#[derive(Component)]
struct CopyMesh(u16);

impl Plugin for SpectatorPlugin {
    fn build(&self, app: &mut App) {
        // The force on the device as an arrow from the gem, 2 cm a newton; no sphere trees.
        let debug = HapticsDebugConfig { tree_depth: None, metres_per_newton: 0.02, ..default() };
        app.insert_resource(ClearColor(Color::srgb(0.05, 0.06, 0.09)))
            .add_plugins(HapticsDebugPlugin)
            .insert_resource(debug)
            .add_systems(Startup, setup)
            .add_systems(Update, (show_copy, take_shot));
    }
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    tools: Query<Entity, With<HapticTool>>,
) {
    commands.spawn((
        Camera3d::default(),
        Transform::from_xyz(0.16, 0.14, 0.26).looking_at(Vec3::new(0.0, -0.01, 0.0), Vec3::Y),
    ));
    // A key light from the upper left and a weak ambient, so the copy's features read as shading.
    commands.spawn((
        DirectionalLight { illuminance: 12_000.0, shadow_maps_enabled: false, ..default() },
        Transform::from_xyz(-0.4, 0.7, 0.5).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.insert_resource(GlobalAmbientLight { brightness: 120.0, ..default() });
    commands.spawn((
        PointLight { intensity: 20_000.0, range: 3.0, shadow_maps_enabled: false, ..default() },
        Transform::from_xyz(0.25, 0.25, 0.2),
    ));
    // The workbench top, under the copies (they stand on y ≈ −0.06).
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(0.5, 0.02, 0.35))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.42, 0.28, 0.16),
            perceptual_roughness: 0.8,
            ..default()
        })),
        Transform::from_xyz(0.0, -0.071, 0.0),
    ));
    // The gemstone: the haptic tool's entity, which follows the device.
    let gem = (
        Mesh3d(meshes.add(
            Sphere::new(TOOL_DIAMETER_M / 2.0).mesh().ico(3).unwrap_or_else(|_| Sphere::new(0.003).mesh().uv(16, 8)),
        )),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.7, 0.9, 1.0),
            emissive: LinearRgba::rgb(0.3, 0.6, 0.9),
            ..default()
        })),
    );
    for tool in &tools {
        commands.entity(tool).insert(gem.clone());
    }
}

/// Shows the copy on the bench (replacing the previous one).
fn show_copy(
    mut commands: Commands,
    bench: Res<BenchView>,
    shown: Query<(Entity, &CopyMesh)>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let wanted = bench.copy.as_ref().map(|c| c.0.0);
    if shown.iter().map(|(_, c)| c.0).next() == wanted && (wanted.is_some() || shown.is_empty()) {
        return;
    }
    for (e, _) in &shown {
        commands.entity(e).despawn();
    }
    let Some((item, mesh, colour)) = bench.copy.as_ref() else { return };
    let positions: Vec<[f32; 3]> = mesh.vertices.clone();
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    // Flat normals: the features read as facets.
    let mut m = Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
        .with_inserted_indices(Indices::U32(indices));
    m.duplicate_vertices();
    m.compute_flat_normals();
    let [r, g, b] = *colour;
    commands.spawn((
        CopyMesh(item.0),
        Mesh3d(meshes.add(m)),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb_u8(r, g, b),
            perceptual_roughness: 0.6,
            double_sided: true,
            cull_mode: None,
            ..default()
        })),
        Transform::IDENTITY,
    ));
}

/// Counts frames once a copy is on the bench, then saves the screenshot and quits.
fn take_shot(
    mut commands: Commands,
    shot: Option<Res<ShotRequest>>,
    bench: Res<BenchView>,
    mut frames: Local<u32>,
    mut exit: MessageWriter<AppExit>,
) {
    let Some(shot) = shot else { return };
    if bench.copy.is_none() && *frames == 0 {
        return;
    }
    *frames += 1;
    if *frames == shot.after_frames {
        log::info!("spectator: screenshot to {}", shot.path.display());
        commands.spawn(Screenshot::primary_window()).observe(save_to_disk(shot.path.clone()));
    }
    // Saving happens a few frames later, on another thread: wait for the file.
    if *frames > shot.after_frames + 5 && shot.path.exists() || *frames > shot.after_frames + 600 {
        exit.write(AppExit::Success);
    }
}
