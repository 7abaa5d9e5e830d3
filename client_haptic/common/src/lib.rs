#![doc = include_str!("../README.md")]
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
