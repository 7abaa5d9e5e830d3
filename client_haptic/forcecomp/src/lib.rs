#![doc = include_str!("../README.md")]
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
pub use penalty::{volumetric_penalty, volumetric_penalty_of};
pub use proxy::{Ball, GodObject, ProxyConfig, TipField, half_space_overlap};
pub use safety::{SafetyConfig, SafetyLayer, SafetyPhase, SafetyStats, Workspace};
pub use texture::Texture;
