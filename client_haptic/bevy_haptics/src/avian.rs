//! The `avian3d` feature: what the tool did to a pushed object goes to its avian3d rigid body.
//!
//! You need this module when your game's physics is avian3d (0.7, its Bevy 0.19 release): give a
//! dynamic `RigidBody` a [`HapticPushable`](crate::HapticPushable) with its mass and a
//! [`HapticCollider`](crate::HapticCollider), and the impulses of each [`ToolPushed`] are applied to it
//! in `PreUpdate` (avian changes the body's velocities at once; its next step moves it). The messages
//! are still written: do not apply them a second time.

use avian3d::prelude::{Forces, WriteRigidBodyForces};
use bevy::prelude::*;

use crate::events::ToolPushed;

/// Applies each frame's pushes to the bodies that have avian3d's forces (`PreUpdate`).
pub(crate) fn apply_pushes(mut pushed: MessageReader<ToolPushed>, mut bodies: Query<Forces>) {
    for push in pushed.read() {
        let Ok(mut body) = bodies.get_mut(push.object) else { continue };
        body.apply_linear_impulse(push.impulse_ns);
        body.apply_angular_impulse(push.angular_impulse_nms);
    }
}
