//! Force effects: forces that do not come from touching a shape — a spring to a point or a line, a
//! viscous region, a constant force, a vibration, a magnetic surface — each a [`HapticEffect`]
//! component on an entity, acting within a radius of it, rendered on the haptic thread at 1 kHz before
//! the contact forces and through the same safety layer (what the OpenHaptics Unity plugin's
//! HapticEffect and CHAI3D's materials give game developers).
//!
//! You need this module to add such a force: spawn a [`HapticEffect`] with a `Transform`. The game
//! thread sends the whole set (at most [`MAX_EFFECTS`]) when one changes or moves; the haptic thread
//! reads the latest set each tick without waiting, allocating or freeing.

use std::sync::Arc;

use bevy::prelude::*;
use collette::InnerSphereTree;
use haptic_common::{ForceOnHapticTick, ForceTorque};
use haptic_rig::WorkspaceMap;

use crate::components::HapticCollider;
use crate::tree::SphereTree;

/// The outer part of an effect's radius over which its force fades out.
const EDGE: f32 = 0.2;

/// Most effects acting at once (more are ignored, with a warning).
pub const MAX_EFFECTS: usize = 32;

/// A force effect, acting on the tool within `radius_m` of the entity (0: everywhere). Its force fades
/// out linearly over the outer fifth of the radius, so crossing the edge never kicks the hand.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Default)]
#[type_path = "bevy_haptics"]
#[require(Transform)]
pub struct HapticEffect {
    /// What force.
    pub kind: EffectKind,
    /// Acts within this distance of the entity's position, m (0: everywhere).
    pub radius_m: f32,
}

impl Default for HapticEffect {
    fn default() -> Self {
        Self { kind: EffectKind::default(), radius_m: 0.0 }
    }
}

/// The kinds of effect (world frame; the entity's `GlobalTransform` places them).
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default)]
#[type_path = "bevy_haptics"]
pub enum EffectKind {
    /// Pulls the tool to the entity's position: `stiffness` × distance, minus `damping` × velocity.
    Spring {
        /// N/m.
        stiffness_n_per_m: f32,
        /// N·s/m.
        damping_ns_per_m: f32,
    },
    /// Pulls the tool to the line through the entity along its local +Y (a guide rail).
    SpringToLine {
        /// N/m.
        stiffness_n_per_m: f32,
        /// N·s/m.
        damping_ns_per_m: f32,
    },
    /// Resists the tool's motion: −`damping` × velocity (a pool of honey).
    Viscous {
        /// N·s/m.
        damping_ns_per_m: f32,
    },
    /// A constant force, world frame (N).
    Constant {
        /// N.
        force_n: Vec3,
    },
    /// A sinusoidal force along the entity's local +Y (a vibrating plate).
    Vibration {
        /// Peak force, N.
        amplitude_n: f32,
        /// Hz.
        frequency_hz: f32,
    },
    /// Pulls the tool towards the surface of the entity's [`HapticCollider`] once within `reach_m` of
    /// it, strongest at the surface: `strength_n` × (1 − distance / reach).
    Magnetic {
        /// Pull at the surface, N.
        strength_n: f32,
        /// Distance from the surface within which it pulls, m.
        reach_m: f32,
    },
}

impl Default for EffectKind {
    fn default() -> Self {
        Self::Viscous { damping_ns_per_m: 2.0 }
    }
}

/// One effect as the haptic thread sees it.
#[derive(Clone, Debug, Default)]
struct Placed {
    effect: Option<HapticEffect>,
    position: Vec3,
    rotation: Quat,
    /// For a magnetic surface: the collider's tree (freed on the game thread: the triple buffer's writer
    /// overwrites old sets there).
    tree: Option<Arc<InnerSphereTree>>,
}

/// Every effect at once (a fixed array: copying a set never allocates).
#[derive(Clone, Debug)]
pub(crate) struct EffectSet {
    effects: [Placed; MAX_EFFECTS],
    len: usize,
}

impl Default for EffectSet {
    fn default() -> Self {
        Self { effects: std::array::from_fn(|_| Placed::default()), len: 0 }
    }
}

/// The game thread's end: writes a new set when one changes.
#[derive(Resource)]
pub(crate) struct EffectsInput(pub(crate) triple_buffer::Input<EffectSet>);

/// A force delegate for the haptic thread reading the latest set (bind it before the rig's force stage).
pub(crate) fn delegate(map: WorkspaceMap) -> (EffectsInput, impl FnMut(&ForceOnHapticTick) + Send + 'static) {
    let (input, mut output) = triple_buffer::triple_buffer(&EffectSet::default());
    // The magnet's tree walk: a few nodes a level (at most 4 children), far below this capacity, so it
    // never grows on the haptic thread.
    let mut stack = Vec::with_capacity(TREE_WALK_CAPACITY);
    let run = move |tick: &ForceOnHapticTick| {
        let set = output.read();
        if set.len == 0 {
            return;
        }
        let tool = map.to_scene(&tick.device.pose).translation;
        let velocity = map.velocity_to_scene(tick.device.linear_velocity);
        let t_s = tick.device.timestamp_us as f32 * 1e-6;
        let mut force = Vec3::ZERO;
        for placed in &set.effects[..set.len] {
            force += effect_force(placed, tool, velocity, t_s, &mut stack);
        }
        tick.add(map.wrench_to_device(ForceTorque { force, torque: Vec3::ZERO }));
    };
    (EffectsInput(input), run)
}

/// Scratch capacity of the magnet's tree walk (see [`collette::partitioning::for_each_leaf_in_sphere`]).
const TREE_WALK_CAPACITY: usize = 1024;

/// The force of one effect on a tool at `tool` moving at `velocity` (world frame), time `t_s`; `stack`
/// is the scratch of a magnet's tree walk.
fn effect_force(placed: &Placed, tool: Vec3, velocity: Vec3, t_s: f32, stack: &mut Vec<u32>) -> Vec3 {
    let Some(effect) = placed.effect else { return Vec3::ZERO };
    let offset = tool - placed.position;
    let fade = if effect.radius_m > 0.0 {
        ((effect.radius_m - offset.length()) / (EDGE * effect.radius_m)).clamp(0.0, 1.0)
    } else {
        1.0
    };
    if fade == 0.0 {
        return Vec3::ZERO;
    }
    let axis = placed.rotation * Vec3::Y;
    fade * match effect.kind {
        EffectKind::Spring { stiffness_n_per_m, damping_ns_per_m } => {
            -stiffness_n_per_m * offset - damping_ns_per_m * velocity
        }
        EffectKind::SpringToLine { stiffness_n_per_m, damping_ns_per_m } => {
            let across = offset - axis * offset.dot(axis);
            let v_across = velocity - axis * velocity.dot(axis);
            -stiffness_n_per_m * across - damping_ns_per_m * v_across
        }
        EffectKind::Viscous { damping_ns_per_m } => -damping_ns_per_m * velocity,
        EffectKind::Constant { force_n } => force_n,
        EffectKind::Vibration { amplitude_n, frequency_hz } => {
            axis * amplitude_n * (std::f32::consts::TAU * frequency_hz * t_s).sin()
        }
        EffectKind::Magnetic { strength_n, reach_m } => {
            let Some(tree) = &placed.tree else { return Vec3::ZERO };
            let local = placed.rotation.inverse() * offset;
            // The nearest inner sphere's surface: where the pull points, and how far. Only spheres within
            // reach can be nearer than `reach_m`: the tree's hierarchy finds them.
            let mut nearest: Option<(Vec3, f32)> = None;
            collette::partitioning::for_each_leaf_in_sphere(tree, local, reach_m, stack, |_, s| {
                let d = s.center.distance(local) - s.radius;
                if nearest.is_none_or(|(_, best)| d < best) {
                    nearest = Some((s.center, d));
                }
            });
            match nearest {
                Some((center, d)) if d > 0.0 && d < reach_m => {
                    let towards = (center - local).normalize_or_zero();
                    placed.rotation * towards * strength_n * (1.0 - d / reach_m)
                }
                _ => Vec3::ZERO,
            }
        }
    }
}

type EffectChanged = Or<(Changed<HapticEffect>, Changed<GlobalTransform>, Changed<HapticCollider>)>;

/// Sends the effects when any changed, moved, came or went (`PostUpdate`).
pub(crate) fn sync_effects(
    input: Option<ResMut<EffectsInput>>,
    trees: Option<Res<Assets<SphereTree>>>,
    effects: Query<(&HapticEffect, &GlobalTransform, Option<&HapticCollider>)>,
    changed: Query<(), EffectChanged>,
    mut removed: RemovedComponents<HapticEffect>,
    mut warned: Local<bool>,
    mut incomplete: Local<bool>,
) {
    let Some(mut input) = input else { return };
    // A magnet whose collider's tree was still loading is sent again until it is there.
    let gone = removed.read().count() > 0;
    if changed.is_empty() && !gone && !*incomplete {
        return;
    }
    *incomplete = false;
    let mut set = EffectSet::default();
    for (effect, transform, collider) in &effects {
        if set.len == MAX_EFFECTS {
            if !*warned {
                warn!("more than {MAX_EFFECTS} haptic effects: the rest are ignored");
                *warned = true;
            }
            break;
        }
        let (_, rotation, position) = transform.to_scale_rotation_translation();
        let tree = collider.zip(trees.as_ref()).and_then(|(c, trees)| trees.get(&c.tree)).map(|t| Arc::clone(&t.tree));
        *incomplete |= matches!(effect.kind, EffectKind::Magnetic { .. }) && tree.is_none();
        set.effects[set.len] = Placed { effect: Some(*effect), position, rotation, tree };
        set.len += 1;
    }
    input.0.write(set);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn placed(kind: EffectKind, radius_m: f32) -> Placed {
        Placed {
            effect: Some(HapticEffect { kind, radius_m }),
            position: Vec3::Y,
            rotation: Quat::IDENTITY,
            tree: None,
        }
    }

    #[test]
    fn a_spring_pulls_back_to_its_point_and_only_within_its_radius() {
        let spring = placed(EffectKind::Spring { stiffness_n_per_m: 100.0, damping_ns_per_m: 0.0 }, 0.05);
        let f = effect_force(&spring, Vec3::new(0.01, 1.0, 0.0), Vec3::ZERO, 0.0, &mut Vec::new());
        assert!((f - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-5, "{f}");
        assert_eq!(
            effect_force(&spring, Vec3::new(0.1, 1.0, 0.0), Vec3::ZERO, 0.0, &mut Vec::new()),
            Vec3::ZERO,
            "outside"
        );
        // Fading over the outer fifth: half way through it, half the force; nothing at the edge.
        let f = effect_force(&spring, Vec3::new(0.045, 1.0, 0.0), Vec3::ZERO, 0.0, &mut Vec::new());
        assert!((f - Vec3::new(-4.5 * 0.5, 0.0, 0.0)).length() < 1e-4, "{f}");
        assert!(effect_force(&spring, Vec3::new(0.05, 1.0, 0.0), Vec3::ZERO, 0.0, &mut Vec::new()).length() < 1e-4);
    }

    #[test]
    fn a_line_spring_pulls_across_its_axis_not_along_it() {
        let rail = placed(EffectKind::SpringToLine { stiffness_n_per_m: 100.0, damping_ns_per_m: 0.0 }, 0.0);
        let f = effect_force(&rail, Vec3::new(0.02, 1.5, 0.0), Vec3::ZERO, 0.0, &mut Vec::new());
        assert!((f - Vec3::new(-2.0, 0.0, 0.0)).length() < 1e-5, "{f}");
    }

    #[test]
    fn a_viscous_region_resists_motion_and_a_vibration_oscillates_along_its_axis() {
        let honey = placed(EffectKind::Viscous { damping_ns_per_m: 5.0 }, 0.0);
        assert_eq!(effect_force(&honey, Vec3::Y, Vec3::X * 0.1, 0.0, &mut Vec::new()), Vec3::X * -0.5);
        let plate = placed(EffectKind::Vibration { amplitude_n: 1.0, frequency_hz: 100.0 }, 0.0);
        let peak = effect_force(&plate, Vec3::Y, Vec3::ZERO, 0.0025, &mut Vec::new());
        assert!((peak - Vec3::Y).length() < 1e-4, "a quarter period: {peak}");
        let constant = placed(EffectKind::Constant { force_n: Vec3::Z }, 0.0);
        assert_eq!(effect_force(&constant, Vec3::ZERO, Vec3::X, 3.0, &mut Vec::new()), Vec3::Z);
    }

    #[test]
    fn a_magnet_pulls_towards_the_surface_within_its_reach() {
        let tree = SphereTree::ball(0.01).tree;
        let magnet =
            Placed { tree: Some(tree), ..placed(EffectKind::Magnetic { strength_n: 2.0, reach_m: 0.02 }, 0.0) };
        // 5 mm from the ball's surface, on its +X side: pulled towards −X with 3/4 of the strength.
        let f = effect_force(&magnet, Vec3::new(0.015, 1.0, 0.0), Vec3::ZERO, 0.0, &mut Vec::new());
        assert!((f - Vec3::new(-1.5, 0.0, 0.0)).length() < 1e-4, "{f}");
        assert_eq!(
            effect_force(&magnet, Vec3::new(0.05, 1.0, 0.0), Vec3::ZERO, 0.0, &mut Vec::new()),
            Vec3::ZERO,
            "beyond reach"
        );
        assert_eq!(
            effect_force(&magnet, Vec3::new(0.005, 1.0, 0.0), Vec3::ZERO, 0.0, &mut Vec::new()),
            Vec3::ZERO,
            "inside"
        );
    }
}
