//! Sphere trees built from an entity's Bevy mesh on the async compute pool, never on the game thread:
//! put a [`SphereTreeFromMesh`] beside a `Mesh3d` (or on a glTF node) and the entity gets its
//! [`HapticCollider`] when the tree is packed.
//!
//! You need this module when a collider's shape is a Bevy mesh rather than a file.

use bevy::mesh::{Mesh, Mesh3d};
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, block_on, poll_once};

use crate::components::HapticCollider;
use crate::tree::{SphereTree, SphereTreeError, tri_mesh};

/// Builds the entity's tree from its `Mesh3d` on the async compute pool, then sets it on its
/// [`HapticCollider`](HapticCollider) (inserted with it if missing). The Bevy counterpart of
/// avian's `ColliderConstructor`: put it beside a mesh, on a glTF node or in a scene file.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Default)]
#[type_path = "bevy_haptics"]
pub struct SphereTreeFromMesh {
    /// Spheres to pack (default 2,000).
    pub spheres: usize,
}

impl Default for SphereTreeFromMesh {
    fn default() -> Self {
        Self { spheres: 2_000 }
    }
}

/// A tree being built for an entity.
#[derive(Component)]
pub(crate) struct BuildingTree(Task<Result<SphereTree, SphereTreeError>>);

/// Starts a build for each new [`SphereTreeFromMesh`] whose mesh is loaded.
pub(crate) fn start_mesh_builds(
    mut commands: Commands,
    meshes: Option<Res<Assets<Mesh>>>,
    pending: Query<(Entity, &SphereTreeFromMesh, &Mesh3d, &GlobalTransform), Without<BuildingTree>>,
) {
    let Some(meshes) = meshes else { return };
    for (entity, from, mesh, transform) in &pending {
        let Some(mesh) = meshes.get(&mesh.0) else { continue };
        // The tree is in the entity's frame; a uniform scale is baked into it (a tree cannot be stretched).
        let scale = transform.compute_transform().scale.max_element();
        let (mesh, spheres) = (mesh.clone(), from.spheres);
        let task = AsyncComputeTaskPool::get()
            .spawn(async move { tri_mesh(&mesh, scale).and_then(|m| SphereTree::build(&m, spheres)) });
        commands.entity(entity).insert(BuildingTree(task));
    }
}

/// Hands finished builds to their entities' colliders.
pub(crate) fn finish_mesh_builds(
    mut commands: Commands,
    mut trees: ResMut<Assets<SphereTree>>,
    mut building: Query<(Entity, &mut BuildingTree, Option<&mut HapticCollider>)>,
) {
    for (entity, mut task, collider) in &mut building {
        let Some(result) = block_on(poll_once(&mut task.0)) else { continue };
        let mut entity_commands = commands.entity(entity);
        entity_commands.remove::<(BuildingTree, SphereTreeFromMesh)>();
        match result {
            Ok(tree) => {
                let handle = trees.add(tree);
                match collider {
                    Some(mut c) => c.tree = handle,
                    None => {
                        entity_commands.insert(HapticCollider::new(handle));
                    }
                }
            }
            Err(e) => error!("no sphere tree for {entity}: {e}"),
        }
    }
}
