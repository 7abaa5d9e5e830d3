//! What the haptic and collision threads exchange through their triple buffers.
//!
//! You need this module to read the rig's data yourself, or to plug in your own collision thread: it only
//! has to publish [`CollisionFrame`]s and read [`ToolPoseMsg`]s.

use std::sync::Arc;

use forcecomp::{Ball, BodyMotion, Material};
use glam::Vec3;
use haptic_common::{ContactSet, Pose};

/// Most objects watched at once (each holds a full contact set in every frame buffer).
pub const MAX_OBJECTS: usize = 4;
/// Most spheres near the tip handed to the 3-DOF proxy in one frame (more are counted, not kept).
pub const MAX_BALLS: usize = 1024;

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
    /// Proxy rendering: how far from the tip (the pose's origin) the proxy may need spheres, scene units.
    pub reach: f32,
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

/// The objects' spheres near the tool tip, for the 3-DOF proxy (fixed capacity, allocated once).
#[derive(Clone, Debug)]
pub struct Balls {
    balls: Box<[Ball]>,
    objects: Box<[u8]>,
    len: usize,
    /// Spheres found but not kept because the set was full.
    pub overflow: u32,
}

impl Default for Balls {
    fn default() -> Self {
        Self { balls: vec![Ball::default(); MAX_BALLS].into(), objects: vec![0; MAX_BALLS].into(), len: 0, overflow: 0 }
    }
}

impl Balls {
    /// Empties the set (keeps its memory).
    pub fn clear(&mut self) {
        self.len = 0;
        self.overflow = 0;
    }

    /// Adds a sphere of the object in slot `object` of the frame; counts it as overflow when full.
    pub fn push(&mut self, ball: Ball, object: usize) {
        if self.len == self.balls.len() {
            self.overflow += 1;
            return;
        }
        self.balls[self.len] = ball;
        self.objects[self.len] = object as u8;
        self.len += 1;
    }

    /// Drops the spheres from the `len`-th on and forgets the overflow (to gather again, nearer).
    pub fn truncate(&mut self, len: usize) {
        self.len = self.len.min(len);
        self.overflow = 0;
    }

    /// The spheres (scene frame).
    pub fn as_slice(&self) -> &[Ball] {
        &self.balls[..self.len]
    }

    /// The frame slot of the object sphere `i` belongs to.
    pub fn object_of(&self, i: usize) -> usize {
        usize::from(self.objects[i])
    }

    /// Number of spheres.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when no sphere is near.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
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
    /// Proxy rendering: the touched objects' spheres near the tool tip (scene frame).
    pub balls: Balls,
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
            balls: Balls::default(),
        }
    }
}

impl CollisionFrame {
    /// The objects touched in this frame.
    pub fn touched(&self) -> &[ObjectContacts] {
        &self.objects[..self.count]
    }

    /// Age at `now_us` of the tool pose this frame was computed from, µs (`u64::MAX` before the first
    /// step).
    pub fn age_us(&self, now_us: u64) -> u64 {
        if self.sequence == 0 { u64::MAX } else { now_us.saturating_sub(self.pose_timestamp_us) }
    }

    /// Number of contacts over all objects (spheres near the tip, with proxy rendering).
    pub fn contact_count(&self) -> usize {
        self.touched().iter().map(|o| o.contacts.len()).sum::<usize>() + self.balls.len()
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

/// Centre of a tree's inner spheres weighted by the mesh volume each stands for (the object's centre
/// of mass at uniform density).
pub fn center_of_mass(tree: &collette::InnerSphereTree) -> Vec3 {
    let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
    for (s, share) in tree.spheres().iter().zip(tree.weights()) {
        let w = s.radius * s.radius * s.radius * share;
        sum += s.center * w;
        weight += w;
    }
    if weight > 0.0 { sum / weight } else { Vec3::ZERO }
}
