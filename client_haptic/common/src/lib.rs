//! Types exchanged between the haptic device layer (`haptico`), the collision layer (`collette`) and
//! the force layer (`forcecomp`), plus the light delegate system that wires them (paper §3.2).
//!
//! You need this crate whenever you connect two of those crates, or replace one of them: it is the only
//! thing they have in common. Everything here is plain data (`Copy` where possible) so it can travel
//! through lock-free latest-value buffers without allocation.
#![warn(missing_docs)]

pub mod contact;
pub mod delegate;
pub mod device;
pub mod events;
pub mod pose;

pub use contact::{Contact, ContactSet, MAX_CONTACTS};
pub use delegate::{BoxedDelegate, DelegateHandle, Delegator, PendingDelegate};
pub use device::{Buttons, DeviceState, ForceTorque};
pub use events::{ForceOnHapticTick, OnCollision, OnTransform};
pub use pose::Pose;
