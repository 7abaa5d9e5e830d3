//! The rooms Vive stands in, built once from the level file: floors, 3 m walls with skirting boards and
//! no ceiling (the sky shows above), moonlit windows in the outer walls, the workbench with Phantom at
//! it, the exit under its sign, and the moonlight. What moves in them is dressed by `world`.

use bevy::prelude::*;
use glam::{Vec2, Vec3};
use heist_shared::level::{Level, WallSet};

use crate::palette::Palette;
use crate::space::{self, BENCH_TOP_M};
use crate::state::ViveState;
use crate::textures::tile_uvs;

/// Height of the walls, metres.
pub const WALL_HEIGHT_M: f32 = 3.0;
/// Moonlight through the open roof, lux (a dim blue wash: the museum is dark but readable).
pub const MOONLIGHT_LUX: f32 = 200.0;
/// The root of the built museum.
#[derive(Component)]
pub(crate) struct Museum;

/// Builds the museum once the level arrived.
pub(crate) fn build_museum(
    mut commands: Commands,
    state: Res<ViveState>,
    built: Query<(), With<Museum>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    palette: Res<Palette>,
) {
    let Some(level) = state.level.as_ref() else { return };
    if !built.is_empty() {
        return;
    }
    spawn_museum(&mut commands, level, state.walls.as_ref(), &mut meshes, &mut materials, &palette);
}

/// Width and height of a window pane, metres, and the height of its centre.
pub const WINDOW_M: (f32, f32, f32) = (1.2, 1.4, 2.0);
/// Space between window centres along an outer wall, metres.
pub const WINDOW_EVERY_M: f32 = 4.0;

/// Where the windows go: along every outer wall (one with no room behind it) longer than a window's
/// spacing, every [`WINDOW_EVERY_M`], centred on the wall, each given as its centre on the floor plan,
/// the wall's direction (radians) and the normal into the room.
pub fn window_spots(level: &Level, walls: &WallSet) -> Vec<(Vec2, f32, Vec2)> {
    let inside = |p: Vec2| level.rooms.iter().any(|r| r.contains(p, 0.0));
    let mut spots = Vec::new();
    for s in &walls.walls {
        let d = s.b - s.a;
        let len = d.length();
        if len < WINDOW_EVERY_M {
            continue;
        }
        let dir = d / len;
        let normal = Vec2::new(-dir.y, dir.x);
        let n = (len / WINDOW_EVERY_M).floor() as usize;
        for i in 0..n {
            let at = s.a + dir * ((i as f32 + 0.5) * len / n as f32);
            // Each pane (and both its edges) must have a room on one side only: outer wall.
            let ends = [at, at + dir * WINDOW_M.0 * 0.5, at - dir * WINDOW_M.0 * 0.5];
            let side =
                |n: Vec2| ends.iter().all(|e| inside(*e + n * 0.3)) && ends.iter().all(|e| !inside(*e - n * 0.3));
            if side(normal) {
                spots.push((at, d.y.atan2(d.x), normal));
            } else if side(-normal) {
                spots.push((at, d.y.atan2(d.x), -normal));
            }
        }
    }
    spots
}

/// Height of the skirting boards along the walls, metres.
pub const SKIRTING_M: f32 = 0.15;
/// Light of the exit sign, lumens (a green glow on the floor around it).
pub const EXIT_SIGN_LM: f32 = 20_000.0;

/// Builds the rooms of `level`: windows, floors, walls with their skirting, the workbench with
/// Phantom at it, the exit, and the moonlight.
fn spawn_museum(
    commands: &mut Commands,
    level: &Level,
    walls: Option<&WallSet>,
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<StandardMaterial>,
    palette: &Palette,
) {
    let root = commands.spawn((Museum, Transform::default(), Visibility::default())).id();
    let windows = walls.map(|w| window_spots(level, w)).unwrap_or_default();
    let looks = Looks::new(materials);
    commands.entity(root).with_children(|museum| {
        spawn_windows(museum, &windows, &looks, palette);
        spawn_floors(museum, level, meshes, palette);
        if let Some(walls) = walls {
            spawn_walls(museum, walls, meshes, palette);
        }
        spawn_bench_and_exit(museum, level, meshes, &looks, palette);
    });
    // Moonlight from above, cold and dim.
    commands.spawn((
        DirectionalLight {
            color: Color::srgb(0.6, 0.7, 1.0),
            illuminance: MOONLIGHT_LUX,
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_xyz(-3.0, 10.0, 6.0).looking_at(Vec3::ZERO, Vec3::Y),
        ChildOf(root),
    ));
}

/// The museum's own materials (besides the palette's): Phantom's cloth, the exit's green, the moonlit
/// window panes.
struct Looks {
    cloth: Handle<StandardMaterial>,
    exit: Handle<StandardMaterial>,
    moonlit: Handle<StandardMaterial>,
}

impl Looks {
    fn new(materials: &mut Assets<StandardMaterial>) -> Self {
        Self {
            cloth: materials.add(StandardMaterial { base_color: Color::srgb(0.15, 0.15, 0.2), ..default() }),
            exit: materials.add(StandardMaterial {
                base_color: Color::srgb(0.1, 0.8, 0.3),
                emissive: LinearRgba::rgb(0.0, 2.0, 0.5),
                ..default()
            }),
            // Moonlit window panes: the night outside glows cold through them.
            moonlit: materials.add(StandardMaterial {
                base_color: Color::srgb(0.02, 0.03, 0.06),
                emissive: LinearRgba::rgb(0.004, 0.006, 0.014),
                perceptual_roughness: 0.3,
                ..default()
            }),
        }
    }
}

fn spawn_windows(museum: &mut ChildSpawnerCommands, windows: &[(Vec2, f32, Vec2)], looks: &Looks, palette: &Palette) {
    let (w, h, centre) = WINDOW_M;
    for (at, along, into) in windows {
        museum.spawn((
            Mesh3d(palette.unit_cube.clone()),
            MeshMaterial3d(looks.moonlit.clone()),
            Transform::from_translation(space::world(*at + *into * 0.085, centre))
                .with_rotation(Quat::from_rotation_y(*along))
                .with_scale(Vec3::new(w, h, 0.02)),
            Name::new("window"),
        ));
    }
}

fn spawn_floors(museum: &mut ChildSpawnerCommands, level: &Level, meshes: &mut Assets<Mesh>, palette: &Palette) {
    for room in &level.rooms {
        let size = room.max - room.min;
        let centre = room.centre();
        museum.spawn((
            Mesh3d(meshes.add(tile_uvs(Cuboid::new(size.x, 0.1, size.y).into(), size))),
            MeshMaterial3d(palette.parquet.clone()),
            Transform::from_translation(space::world(centre, -0.05)),
            Name::new(format!("floor {}", room.id)),
        ));
    }
}

fn spawn_walls(museum: &mut ChildSpawnerCommands, walls: &WallSet, meshes: &mut Assets<Mesh>, palette: &Palette) {
    for (segments, material, height) in
        [(&walls.walls, &palette.plaster, WALL_HEIGHT_M), (&walls.closed_doors, &palette.wood, 2.2)]
    {
        for s in segments {
            let d = s.b - s.a;
            let len = d.length();
            if len < 1e-3 {
                continue;
            }
            let mid = (s.a + s.b) * 0.5;
            let along = Quat::from_rotation_y(d.y.atan2(d.x));
            museum.spawn((
                Mesh3d(meshes.add(tile_uvs(Cuboid::new(len + 0.15, height, 0.15).into(), Vec2::new(len, height)))),
                MeshMaterial3d(material.clone()),
                Transform::from_translation(space::world(mid, height * 0.5)).with_rotation(along),
            ));
            // A dark skirting board along both faces (one shared cube, sized by its transform).
            museum.spawn((
                Mesh3d(palette.unit_cube.clone()),
                MeshMaterial3d(palette.wood.clone()),
                Transform::from_translation(space::world(mid, SKIRTING_M * 0.5))
                    .with_rotation(along)
                    .with_scale(Vec3::new(len + 0.17, SKIRTING_M, 0.19)),
            ));
        }
    }
}

/// The workbench, Phantom at it, and the exit marker under its sign.
fn spawn_bench_and_exit(
    museum: &mut ChildSpawnerCommands,
    level: &Level,
    meshes: &mut Assets<Mesh>,
    looks: &Looks,
    palette: &Palette,
) {
    museum.spawn((
        Mesh3d(meshes.add(Cuboid::new(1.4, BENCH_TOP_M, 0.8))),
        MeshMaterial3d(palette.wood.clone()),
        Transform::from_translation(space::world(level.workbench, BENCH_TOP_M * 0.5)),
        Name::new("workbench"),
    ));
    let phantom_at = level.workbench + Vec2::new(0.0, 0.75);
    museum.spawn((
        Mesh3d(meshes.add(Capsule3d::new(0.25, 0.7))),
        MeshMaterial3d(looks.cloth.clone()),
        Transform::from_translation(space::world(phantom_at, 0.75)),
        Name::new("Phantom"),
    ));
    museum.spawn((
        Mesh3d(meshes.add(Sphere::new(0.13))),
        MeshMaterial3d(looks.cloth.clone()),
        Transform::from_translation(space::world(phantom_at, 1.45)),
    ));
    museum.spawn((
        Mesh3d(meshes.add(Cylinder::new(0.5, 0.02))),
        MeshMaterial3d(looks.exit.clone()),
        Transform::from_translation(space::world(level.exit, 0.01)),
        Name::new("exit"),
    ));
    museum.spawn((
        Mesh3d(palette.unit_cube.clone()),
        MeshMaterial3d(looks.exit.clone()),
        Transform::from_translation(space::world(level.exit, 2.4)).with_scale(Vec3::new(0.5, 0.2, 0.05)),
        Name::new("exit sign"),
    ));
    museum.spawn((
        PointLight {
            color: Color::srgb(0.2, 1.0, 0.4),
            intensity: EXIT_SIGN_LM,
            range: 5.0,
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_translation(space::world(level.exit, 2.2)),
    ));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_look_out_of_the_outer_walls_only_and_face_into_their_room() {
        let level = Level::museum();
        let walls = heist_shared::level::WallSet::new(&level);
        let spots = window_spots(&level, &walls);
        let outside = |p: Vec2| !level.rooms.iter().any(|r| r.contains(p, 0.0));
        assert!(spots.len() >= 12, "the museum's outer walls have windows: {}", spots.len());
        for (at, _, into) in &spots {
            assert!(outside(*at - *into * 0.3), "{at}: outside behind the window");
            assert!(!outside(*at + *into * 0.3), "{at}: a room in front of it");
        }
        // Every room with an outer wall of a window's spacing gets one; the walls between rooms none.
        for room in &level.rooms {
            assert!(
                spots.iter().any(|(at, _, into)| room.contains(*at + *into * 0.3, 0.0)),
                "{} has a window",
                room.id
            );
        }
        let between = Vec2::new(10.0, 6.0); // the lobby–west gallery wall
        assert!(spots.iter().all(|(at, ..)| at.distance(between) > 1.0));
    }
}
