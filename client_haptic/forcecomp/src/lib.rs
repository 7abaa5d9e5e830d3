//! forcecomp: forces and torques from contacts (paper §3.5, §4.2).
//!
//! - [`penalty`]: the volumetric penalty force (Eq. 1) and torque (Eq. 2) from an Inner Sphere Tree
//!   contact set, with per-object [`Material`]s;
//! - [`texture`]: ridges on a material's surface, felt on top of either rendering;
//! - [`proxy`]: the 3-DOF god-object (proxy) force for point tools on an Inner Sphere Tree's spheres;
//! - [`coupling`]: virtual coupling between the device and a simulated tool, for stable 6-DOF rendering;
//! - [`safety`]: the layer applied last, always — clamps, force-rate limit, start-up engagement,
//!   watchdog, NaN/inf removal.
//!
//! Everything takes `dt` and inputs and returns data: no clock, no thread, no allocation in the
//! per-tick functions. It depends only on `haptic_common`; bind its functions to the haptic thread's
//! `ForceOnHapticTick` event (see `haptic_rig`).
#![warn(missing_docs)]

pub mod coupling;
pub mod error;
pub mod material;
pub mod penalty;
pub mod proxy;
pub mod safety;
pub mod texture;

pub use coupling::{CouplingConfig, VirtualCoupling};
pub use error::{ForceCompError, Result};
pub use material::{BodyMotion, Material};
pub use penalty::volumetric_penalty;
pub use proxy::{Ball, GodObject, ProxyConfig};
pub use safety::{SafetyConfig, SafetyLayer, SafetyPhase, SafetyStats, Workspace};
pub use texture::Texture;
