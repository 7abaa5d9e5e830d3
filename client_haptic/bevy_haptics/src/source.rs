//! Trees named by a file path and its settings, so a set-up can live in a scene file or on a glTF node:
//! put a [`SphereTreeSource`] on the entity and the asset server loads its tree for the entity's
//! [`HapticTool`] or [`HapticCollider`].
//!
//! You need this module to write a haptic set-up as data. A `Handle<SphereTree>` can be written in a
//! scene file too (`tree: Path("trees/box.ist")`), but a path alone carries no loader settings: an `.obj`
//! mesh in other units than metres, or packed with another sphere count, needs this component.

use bevy::prelude::*;

use crate::components::{HapticCollider, HapticTool};
use crate::tree::{SphereTree, SphereTreeSettings};

/// Where an entity's sphere tree comes from: an asset path (an `.ist` tree or an `.obj` mesh) and, for a
/// mesh, how to pack it. The tree goes to the entity's [`HapticTool`] if it has one, else to its
/// [`HapticCollider`] (inserted if missing). Reflected and registered: usable from scene files.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default)]
#[type_path = "bevy_haptics"]
pub struct SphereTreeSource {
    /// The asset path, relative to the asset folder (e.g. `meshes/bunny.obj`).
    pub path: String,
    /// Spheres to pack a mesh with (default 2,000; a tree file keeps its own).
    pub spheres: usize,
    /// Metres per unit of a mesh (default 1; a tree file is in metres).
    pub scale: f32,
    /// Voxels of a mesh's surface grid along its longest side (default 0: none; see
    /// [`SphereTreeSettings::surface_voxels`]).
    pub surface_voxels: usize,
    /// Longest edge of a mesh's surface shell, m (default 0: none; see
    /// [`SphereTreeSettings::shell_edge_m`]).
    pub shell_edge_m: f32,
}

impl Default for SphereTreeSource {
    fn default() -> Self {
        let SphereTreeSettings { spheres, scale, surface_voxels, shell_edge_m } = SphereTreeSettings::default();
        Self { path: String::new(), spheres, scale, surface_voxels, shell_edge_m }
    }
}

type Source<'a> = (Entity, &'a SphereTreeSource, Option<&'a mut HapticTool>, Option<&'a mut HapticCollider>);

/// Loads the tree of each new or changed [`SphereTreeSource`] and gives it to the entity's tool or
/// collider (`PostUpdate`, before the trees go to the threads).
pub(crate) fn load_sources(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut sources: Query<Source, Changed<SphereTreeSource>>,
) {
    for (entity, source, tool, collider) in &mut sources {
        let settings = SphereTreeSettings {
            spheres: source.spheres,
            scale: source.scale,
            surface_voxels: source.surface_voxels,
            shell_edge_m: source.shell_edge_m,
        };
        let tree: Handle<SphereTree> = assets
            .load_builder()
            .with_settings(move |s: &mut SphereTreeSettings| *s = settings)
            .load(source.path.clone());
        match (tool, collider) {
            (Some(mut tool), _) => tool.tree = Some(tree),
            (None, Some(mut collider)) => collider.tree = tree,
            (None, None) => {
                commands.entity(entity).insert(HapticCollider::new(tree));
            }
        }
    }
}
