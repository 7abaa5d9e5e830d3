#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

pub mod bench;
pub mod collision;
pub mod error;
pub mod force;
pub mod lockstep;
pub mod push;
pub mod rig;
mod scene;
pub mod spec;
pub mod workspace;

pub use collision::{CollisionConfig, StepTiming};
pub use error::{Result, RigError};
pub use force::{ForceSample, ObjectContact, ProxyRendering, Rendering, RigTelemetry};
pub use push::{ObjectPush, PushCoupling};
pub use rig::{HapticRig, RigConfig, safety_for};
pub use spec::{MAX_OBJECTS, MAX_PAIR_WATCHERS, ObjectSpec, PairContact, ToolSpec};
pub use workspace::WorkspaceMap;

pub use collette::pipeline::TrackTiming;
