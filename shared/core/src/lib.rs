//! What the Phantom Heist server and both clients agree on: the protocol, the level format, the
//! game constants, and the procedural artifacts (haptic geometry, materials, briefings).
#![warn(missing_docs)]

pub mod artifact;
pub mod level;
pub mod protocol;
pub mod rules;
