//! What the haptic side tells the game, with entities: the device's transform each frame (the paper's
//! OnTransform) and contacts starting, going on and ending (OnCollision). Each is both a message (read
//! it with a `MessageReader` in any system) and an observer event, triggered on the touched object
//! (`commands.entity(bunny).observe(|c: On<ContactStarted>| ..)` or a global `app.add_observer`).
//!
//! You need this module to react to touch on the game thread. Code that must run at 1 kHz binds to the
//! haptic thread instead ([`HapticDelegates`](crate::HapticDelegates)).

use bevy::prelude::*;

/// The tool moved with the device (once a frame, in `PreUpdate`; the paper's OnTransform as the game
/// sees it). Triggered on the tool entity.
#[derive(Message, EntityEvent, Clone, Copy, Debug, PartialEq)]
pub struct ToolMoved {
    /// The tool entity.
    #[event_target]
    pub tool: Entity,
    /// Where the tool is, world frame (the coupled tool with 6-DOF rendering, the proxy on the surface
    /// with 3-DOF rendering, else the device).
    pub transform: Transform,
    /// Force sent to the device on the last haptic tick, device frame, N.
    pub force_n: Vec3,
    /// Torque sent to the device on the last haptic tick, device frame, N·m.
    pub torque_nm: Vec3,
}

/// The tool started touching an object (first frame of a contact). Triggered on the object.
#[derive(Message, EntityEvent, Clone, Copy, Debug, PartialEq)]
pub struct ContactStarted {
    /// The touched object.
    #[event_target]
    pub object: Entity,
    /// The tool.
    pub tool: Entity,
    /// What the contact is like now.
    pub contact: ContactData,
}

/// The tool is still touching an object (every frame of a contact after the first). Triggered on the
/// object.
#[derive(Message, EntityEvent, Clone, Copy, Debug, PartialEq)]
pub struct ContactOngoing {
    /// The touched object.
    #[event_target]
    pub object: Entity,
    /// The tool.
    pub tool: Entity,
    /// What the contact is like now.
    pub contact: ContactData,
}

/// The tool stopped touching an object (or the object stopped being collidable). Triggered on the
/// object when it still exists.
#[derive(Message, EntityEvent, Clone, Copy, Debug, PartialEq)]
pub struct ContactEnded {
    /// The object that was touched.
    #[event_target]
    pub object: Entity,
    /// The tool.
    pub tool: Entity,
}

/// A contact as the latest haptic tick saw it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Reflect)]
#[type_path = "bevy_haptics"]
pub struct ContactData {
    /// Overlapping sphere pairs (volumetric rendering) or the object's spheres near the tip (3-DOF proxy).
    pub pairs: u32,
    /// Overlap volume of tool and object, m³ (0 with the 3-DOF proxy).
    pub volume_m3: f32,
    /// Force the object puts on the tool, world frame, N (before coupling and safety; 0 without
    /// `ForceCompPlugin`).
    pub force_n: Vec3,
    /// Torque the object puts on the tool about the tool's centre of mass, world frame, N·m.
    pub torque_nm: Vec3,
}

/// Two colliders a [`CollisionWatcher`](crate::CollisionWatcher) watches began to overlap. Triggered on
/// the watcher entity.
#[derive(Message, EntityEvent, Clone, Copy, Debug, PartialEq)]
pub struct PairContactStarted {
    /// The watcher.
    #[event_target]
    pub watcher: Entity,
    /// One collider.
    pub a: Entity,
    /// The other.
    pub b: Entity,
    /// Their overlap volume when it started, m³.
    pub volume_m3: f32,
    /// Overlapping sphere pairs when it started.
    pub pairs: u32,
}

/// Two watched colliders stopped overlapping (or one of them stopped being collidable, or the watcher
/// went). Triggered on the watcher entity when it still exists.
#[derive(Message, EntityEvent, Clone, Copy, Debug, PartialEq)]
pub struct PairContactEnded {
    /// The watcher.
    #[event_target]
    pub watcher: Entity,
    /// One collider.
    pub a: Entity,
    /// The other.
    pub b: Entity,
}

/// What the tool did to a [`HapticPushable`](crate::HapticPushable) since the last frame (written in
/// `PreUpdate`, for each object the tool pushed or whose haptic copy is still settling): apply the
/// impulses to its rigid body once (the `avian3d` feature does it for an avian3d body). Triggered on the
/// object.
#[derive(Message, EntityEvent, Clone, Copy, Debug, PartialEq)]
pub struct ToolPushed {
    /// The pushed object.
    #[event_target]
    pub object: Entity,
    /// Linear impulse at its centre of mass, world frame, N·s.
    pub impulse_ns: Vec3,
    /// Angular impulse about its centre of mass, world frame, N·m·s.
    pub angular_impulse_nms: Vec3,
    /// The time the impulses were gathered over, s (their mean force is `impulse_ns / duration_s`).
    pub duration_s: f32,
}
