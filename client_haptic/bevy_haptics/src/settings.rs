//! The settings the plugins leave for the threads when they start: the collision thread's (from
//! [`CollettePlugin`](crate::CollettePlugin)) and the force stage's (from
//! [`ForceCompPlugin`](crate::ForceCompPlugin)); a part left out leaves none.
//!
//! You need this module to change them before the app starts (they are resources).

use bevy::prelude::*;
use haptic_rig::{ProxyRendering, PushCoupling, Rendering};
use haptico::DeviceSpecs;

/// The collision thread's settings (present when [`CollettePlugin`](crate::CollettePlugin) is added).
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct CollisionSettings(pub haptic_rig::CollisionConfig);

/// How contact forces are rendered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Reflect)]
#[type_path = "bevy_haptics"]
pub enum RenderingMode {
    /// By the device: volumetric when it renders torque, else the 3-DOF proxy.
    #[default]
    Auto,
    /// The tool's inner spheres against the object's (force and torque, through a virtual coupling).
    Volumetric,
    /// The 3-DOF god-object: the tool's tip held on the surface (force only).
    Proxy,
}

/// The force stage's settings (present when [`ForceCompPlugin`](crate::ForceCompPlugin) is added).
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct ForceRendering {
    /// How contact forces are rendered.
    pub mode: RenderingMode,
    /// How the 3-DOF proxy feels materials.
    pub proxy: ProxyRendering,
    /// How pushed objects follow the game's bodies.
    pub pushes: PushCoupling,
}

impl ForceRendering {
    /// The rendering for `specs`.
    pub(crate) fn resolve(&self, specs: &DeviceSpecs) -> (Rendering, ProxyRendering) {
        let rendering = match self.mode {
            RenderingMode::Volumetric => Rendering::Coupled,
            RenderingMode::Proxy => Rendering::Proxy,
            RenderingMode::Auto if specs.renders_torque() => Rendering::Coupled,
            RenderingMode::Auto => Rendering::Proxy,
        };
        (rendering, self.proxy)
    }
}
