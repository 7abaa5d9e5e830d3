//! What the haptic and collision threads exchange through their triple buffers.
//!
//! You need this module to read the rig's data yourself, or to plug in your own collision thread: it only
//! has to publish [`CollisionFrame`]s and read [`ToolPoseMsg`]s.

use std::sync::Arc;

use forcecomp::{BodyMotion, Material};
use glam::Vec3;
use haptic_common::{ContactSet, Pose};

/// Most objects watched at once (each holds a full contact set in every frame buffer).
pub const MAX_OBJECTS: usize = 4;

/// The tool's pose, sent by the haptic thread every tick (latest value wins).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ToolPoseMsg {
    /// Haptic tick that produced it.
    pub tick: u64,
    /// Pose of the (simulated) tool in the scene.
    pub pose: Pose,
    /// Linear velocity in the scene, units/s.
    pub linear_velocity: Vec3,
    /// Angular velocity in the scene, rad/s.
    pub angular_velocity: Vec3,
    /// Time of the device sample it follows, µs on the haptic clock.
    pub timestamp_us: u64,
}

/// Contacts of the tool with one object, with what the force law needs to know about the object.
#[derive(Clone, Debug, Default)]
pub struct ObjectContacts {
    /// Object id given by the game.
    pub object_id: u32,
    /// The object's material.
    pub material: Material,
    /// How the object moves (scene).
    pub motion: BodyMotion,
    /// The overlapping sphere pairs (tool = A, object = B).
    pub contacts: ContactSet,
}

/// One collision step's result, published by the collision thread.
#[derive(Clone, Debug)]
pub struct CollisionFrame {
    /// Step counter (0 = no step yet).
    pub sequence: u64,
    /// Timestamp of the tool pose the step used, µs on the haptic clock.
    pub pose_timestamp_us: u64,
    /// The tool pose the step used (scene).
    pub tool_pose: Pose,
    /// The tool's centre of mass in its own frame.
    pub tool_center_of_mass: Vec3,
    /// The tool's material.
    pub tool_material: Material,
    /// Time the step took, µs.
    pub step_us: u32,
    /// Objects with contacts in `objects[..count]`.
    pub count: usize,
    /// Per-object contacts, `MAX_OBJECTS` preallocated.
    pub objects: Vec<ObjectContacts>,
}

impl Default for CollisionFrame {
    fn default() -> Self {
        Self {
            sequence: 0,
            pose_timestamp_us: 0,
            tool_pose: Pose::IDENTITY,
            tool_center_of_mass: Vec3::ZERO,
            tool_material: Material::default(),
            step_us: 0,
            count: 0,
            objects: (0..MAX_OBJECTS).map(|_| ObjectContacts::default()).collect(),
        }
    }
}

impl CollisionFrame {
    /// The objects touched in this frame.
    pub fn touched(&self) -> &[ObjectContacts] {
        &self.objects[..self.count]
    }

    /// Number of contacts over all objects.
    pub fn contact_count(&self) -> usize {
        self.touched().iter().map(|o| o.contacts.len()).sum()
    }
}

/// The tool: its Inner Sphere Tree, centre of mass and material.
#[derive(Clone, Debug)]
pub struct ToolSpec {
    /// The tree, in the tool's frame (scene units).
    pub tree: Arc<collette::InnerSphereTree>,
    /// Centre of mass in the tool's frame.
    pub center_of_mass: Vec3,
    /// Material.
    pub material: Material,
}

impl ToolSpec {
    /// A tool whose centre of mass is the volume-weighted centre of its inner spheres.
    pub fn new(tree: Arc<collette::InnerSphereTree>, material: Material) -> Self {
        let center_of_mass = center_of_mass(&tree);
        Self { tree, center_of_mass, material }
    }
}

/// A watched object.
#[derive(Clone, Debug)]
pub struct ObjectSpec {
    /// Id chosen by the game (reported in contacts).
    pub id: u32,
    /// The tree, in the object's frame.
    pub tree: Arc<collette::InnerSphereTree>,
    /// Pose in the scene.
    pub pose: Pose,
    /// Material.
    pub material: Material,
}

/// Volume-weighted centre of a tree's inner spheres (its centre of mass at uniform density).
pub fn center_of_mass(tree: &collette::InnerSphereTree) -> Vec3 {
    let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
    for s in tree.spheres() {
        let w = s.radius * s.radius * s.radius;
        sum += s.center * w;
        weight += w;
    }
    if weight > 0.0 { sum / weight } else { Vec3::ZERO }
}
