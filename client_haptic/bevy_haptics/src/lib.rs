#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

#[cfg(feature = "avian3d")]
mod avian;
mod components;
#[cfg(feature = "debug")]
pub mod debug;
mod device;
mod effects;
mod events;
mod frame;
mod mesh_build;
mod plugins;
mod runtime;
mod settings;
mod source;
mod stats;
mod tree;

pub use components::{
    CollisionVolume, CollisionWatcher, ForceComponent, HapticCollider, HapticPushable, HapticTool, Ridges,
};
#[cfg(feature = "debug")]
pub use debug::{HapticsDebugConfig, HapticsDebugPlugin};
pub use device::{DeviceError, DeviceKind, HapticDevice, HapticDeviceLink, SimulatedHand};
pub use effects::{EffectKind, HapticEffect, MAX_EFFECTS};
pub use events::{
    ContactData, ContactEnded, ContactOngoing, ContactStarted, PairContactEnded, PairContactStarted, ToolMoved,
    ToolPushed,
};
pub use frame::HapticFrame;
pub use mesh_build::SphereTreeFromMesh;
pub use plugins::{CollettePlugin, ForceCompPlugin, HapticoPlugin, HapticsPlugins, HapticsSystems};
pub use runtime::{HapticDelegates, HapticStatus};
pub use settings::{CollisionSettings, ForceRendering, RenderingMode};
pub use source::SphereTreeSource;
pub use stats::{HapticStats, WINDOW_US, WindowedRate};
pub use tree::{SphereTree, SphereTreeError, SphereTreeLoader, SphereTreeSettings, tri_mesh};

/// The libraries underneath, for what the plugins do not wrap (your own device, the force delegates'
/// payloads, the rig's settings).
pub mod libs {
    pub use {collette, forcecomp, haptic_common, haptic_rig, haptico};
}

/// Everything a game usually needs.
pub mod prelude {
    pub use crate::{
        CollettePlugin, CollisionVolume, CollisionWatcher, ContactEnded, ContactOngoing, ContactStarted, EffectKind,
        ForceCompPlugin, ForceComponent, HapticCollider, HapticDelegates, HapticDevice, HapticEffect, HapticFrame,
        HapticPushable, HapticStats, HapticStatus, HapticTool, HapticoPlugin, HapticsPlugins, HapticsSystems,
        PairContactEnded, PairContactStarted, RenderingMode, SimulatedHand, SphereTree, SphereTreeFromMesh,
        SphereTreeSettings, SphereTreeSource, ToolMoved, ToolPushed,
    };
    pub use haptic_common::{ForceOnHapticTick, ForceTorque};
    pub use haptico::steer::HandGoal;
}
