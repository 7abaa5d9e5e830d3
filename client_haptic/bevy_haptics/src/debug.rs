//! Gizmos for the haptic scene: the tool, each collider's sphere tree at a chosen depth, the touched
//! objects, and the force and torque on the device (feature `debug`).
//!
//! You need this module to see what the collision thread measures: add [`HapticsDebugPlugin`] beside
//! [`HapticsPlugins`](crate::HapticsPlugins) and set [`HapticsDebugConfig`]. Gizmos reach the screen
//! when Bevy renders them (its `bevy_gizmos_render` feature).

use std::collections::HashMap;

use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use collette::{InnerSphereTree, Sphere};

use crate::components::{HapticCollider, HapticTool};
use crate::events::{ContactOngoing, ContactStarted, ToolMoved};
use crate::tree::SphereTree;

/// What the debug gizmos draw.
#[derive(Resource, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Resource, Default)]
#[type_path = "bevy_haptics"]
pub struct HapticsDebugConfig {
    /// Depth at which trees are drawn: 0 is each tree's root sphere, deeper levels their children, the
    /// leaves' inner spheres below the last level (default 2; `None`: no trees).
    pub tree_depth: Option<usize>,
    /// Length of the force arrow per newton, m (default 0.02).
    pub metres_per_newton: f32,
    /// Length of the torque arrow per newton-metre, m (default 1).
    pub metres_per_newton_metre: f32,
    /// Colour of the trees.
    pub tree_color: Color,
    /// Colour of a touched object's tree.
    pub touched_color: Color,
}

impl Default for HapticsDebugConfig {
    fn default() -> Self {
        Self {
            tree_depth: Some(2),
            metres_per_newton: 0.02,
            metres_per_newton_metre: 1.0,
            tree_color: Color::srgb(0.3, 0.6, 1.0),
            touched_color: Color::srgb(1.0, 0.8, 0.2),
        }
    }
}

/// Draws the haptic scene with gizmos (see [`HapticsDebugConfig`]).
#[derive(Default)]
pub struct HapticsDebugPlugin;

impl Plugin for HapticsDebugPlugin {
    fn build(&self, app: &mut App) {
        // The messages it reads (registered again by the other plugins: adding a message is idempotent).
        app.add_message::<ToolMoved>().add_message::<ContactStarted>().add_message::<ContactOngoing>();
        app.init_resource::<HapticsDebugConfig>()
            .register_type::<HapticsDebugConfig>()
            .init_resource::<Levels>()
            .add_systems(PostUpdate, (draw_trees, draw_wrench).after(TransformSystems::Propagate));
    }
}

/// Each tree's spheres at the configured depth (computed once per tree and depth).
#[derive(Resource, Default)]
struct Levels(HashMap<(AssetId<SphereTree>, usize), Vec<Sphere>>);

/// The bounding spheres `depth` levels below the root (a leaf reached earlier gives its inner spheres).
pub fn spheres_at_depth(tree: &InnerSphereTree, depth: usize) -> Vec<Sphere> {
    let nodes = tree.nodes();
    let mut level = vec![0usize];
    let mut out = Vec::new();
    for _ in 0..depth {
        let mut next = Vec::new();
        for &i in &level {
            let node = &nodes[i];
            if node.leaf {
                out.extend_from_slice(&tree.spheres()[node.range()]);
            } else {
                next.extend(node.range());
            }
        }
        level = next;
    }
    out.extend(level.iter().map(|&i| nodes[i].bound));
    out
}

/// The objects touched this frame.
#[derive(SystemParam)]
struct Touches<'w, 's> {
    started: MessageReader<'w, 's, ContactStarted>,
    ongoing: MessageReader<'w, 's, ContactOngoing>,
}

impl Touches<'_, '_> {
    fn objects(&mut self) -> Vec<Entity> {
        let started = self.started.read().map(|c| c.object);
        started.chain(self.ongoing.read().map(|c| c.object)).collect()
    }
}

fn draw_trees(
    mut gizmos: Gizmos,
    config: Res<HapticsDebugConfig>,
    trees: Option<Res<Assets<SphereTree>>>,
    mut levels: ResMut<Levels>,
    colliders: Query<(Entity, &HapticCollider, &GlobalTransform)>,
    tools: Query<(&HapticTool, &GlobalTransform)>,
    mut touches: Touches,
) {
    let (Some(depth), Some(trees)) = (config.tree_depth, trees) else { return };
    let touched = touches.objects();
    let handles = colliders
        .iter()
        .map(|(e, c, t)| (Some(&c.tree), t, touched.contains(&e)))
        .chain(tools.iter().map(|(tool, t)| (tool.tree.as_ref(), t, false)));
    for (handle, transform, touched) in handles {
        let color = if touched { config.touched_color } else { config.tree_color };
        let Some(handle) = handle else {
            continue;
        };
        let Some(tree) = trees.get(handle) else { continue };
        let spheres = levels.0.entry((handle.id(), depth)).or_insert_with(|| spheres_at_depth(&tree.tree, depth));
        let (_, rotation, translation) = transform.to_scale_rotation_translation();
        for s in spheres.iter() {
            let at = Isometry3d::new(translation + rotation * s.center, rotation);
            gizmos.sphere(at, s.radius, color);
        }
    }
    for (tool, transform) in &tools {
        if tool.tree.is_none() {
            gizmos.sphere(Isometry3d::from_translation(transform.translation()), tool.tip_radius_m, Color::WHITE);
        }
    }
}

fn draw_wrench(mut gizmos: Gizmos, config: Res<HapticsDebugConfig>, mut moved: MessageReader<ToolMoved>) {
    let Some(m) = moved.read().last() else { return };
    let at = m.transform.translation;
    if m.force_n.length() > 1e-3 {
        gizmos.arrow(at, at + m.force_n * config.metres_per_newton, Color::srgb(1.0, 0.25, 0.2));
    }
    if m.torque_nm.length() > 1e-5 {
        gizmos.arrow(at, at + m.torque_nm * config.metres_per_newton_metre, Color::srgb(0.3, 0.5, 1.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trees_levels_cover_it_from_the_root_down_to_its_inner_spheres() {
        let tree = SphereTree::gem(0.02, 300).expect("a gem packs").tree;
        let root = spheres_at_depth(&tree, 0);
        assert_eq!(root.len(), 1);
        let deep = spheres_at_depth(&tree, 64);
        assert_eq!(deep.len(), tree.spheres().len(), "below the last level: every inner sphere");
        let mid = spheres_at_depth(&tree, 2);
        assert!(mid.len() > 1 && mid.len() < deep.len());
        // Every inner sphere lies within the root's bound.
        for s in &deep {
            assert!(s.center.distance(root[0].center) + s.radius <= root[0].radius * 1.001 + 1e-6);
        }
    }
}
