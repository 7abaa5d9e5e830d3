//! haptic_rig: the wiring of haptico, collette and forcecomp (the paper's EventHandler, §3.6).
//!
//! Three threads: the game thread steers a [`HapticRig`]; the haptic thread (haptico, 1 kHz) reads the
//! device and runs the [`force::ForceStage`] on `ForceOnHapticTick` (penalty force or 3-DOF proxy,
//! virtual coupling, safety); the collision thread (collette's pipeline, paced by [`collision`], 1 kHz)
//! turns the latest tool pose into each watched object's contacts (or its spheres near the tip). The threads exchange latest values through triple buffers and commands
//! through fixed-capacity ring buffers; nothing on either real-time thread allocates, locks or logs in
//! steady state.
//!
//! You need this crate to run the whole loop, or as the example to copy when you swap one part.
//! [`bench`] holds the pieces of the `haptic-bench` binary (windowed rates, CSV, the Fig. 9 plot).
#![warn(missing_docs)]

pub mod bench;
pub mod collision;
pub mod error;
pub mod force;
pub mod lockstep;
pub mod rig;
mod scene;
pub mod spec;
pub mod workspace;

pub use collision::{CollisionConfig, StepTiming};
pub use error::{Result, RigError};
pub use force::{ForceSample, ProxyRendering, Rendering, RigTelemetry};
pub use rig::{HapticRig, RigConfig};
pub use spec::{MAX_OBJECTS, ObjectSpec, ToolSpec};
pub use workspace::WorkspaceMap;
