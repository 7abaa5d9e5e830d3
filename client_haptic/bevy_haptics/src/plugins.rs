//! The plugin group and its three parts (the paper's HAPTICO, COLLETTE and FORCECOMP), each of which
//! can be left out or replaced.
//!
//! You need this module to add haptics to an app: `app.add_plugins(HapticsPlugins::default())`.
//! - [`HapticoPlugin`] alone: the device and the 1 kHz haptic thread, the tool following the device, your
//!   force delegates ([`HapticDelegates`](crate::HapticDelegates)) behind the device's safety limits.
//! - with [`CollettePlugin`]: the collision thread, sphere-tree assets, colliders and contact events.
//! - with [`ForceCompPlugin`]: contact forces (volumetric penalty with torque through a virtual
//!   coupling, or the 3-DOF proxy, by the device's DOF). Without it contacts are reported but only your
//!   delegates push the device.

use bevy::app::PluginGroupBuilder;
use bevy::asset::ReflectHandle;
use bevy::prelude::*;
use haptic_rig::{ProxyRendering, PushCoupling};

use crate::components::{
    CollisionVolume, CollisionWatcher, ForceComponent, HapticCollider, HapticPushable, HapticTool, Ridges,
};
use crate::device::HapticDevice;
use crate::effects::{self, EffectKind, HapticEffect};
use crate::events::{
    ContactData, ContactEnded, ContactOngoing, ContactStarted, PairContactEnded, PairContactStarted, ToolMoved,
    ToolPushed,
};
use crate::frame::HapticFrame;
use crate::mesh_build::{self, SphereTreeFromMesh};
use crate::runtime::{self, HapticDelegates, HapticStatus};
use crate::settings::{CollisionSettings, ForceRendering, RenderingMode};
use crate::source::{self, SphereTreeSource};
use crate::stats::HapticStats;
use crate::tree::{SphereTree, SphereTreeLoader};

/// System sets of the haptics plugins, to order your systems against them.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HapticsSystems {
    /// `PreUpdate`: the tool moves to the device, contacts and the loop's figures come in.
    Read,
    /// `PostUpdate`, after transforms propagate: trees, poses, materials and the volume go out.
    Write,
}

/// The whole stack: [`HapticoPlugin`], [`CollettePlugin`], [`ForceCompPlugin`].
#[derive(Default)]
pub struct HapticsPlugins;

impl PluginGroup for HapticsPlugins {
    fn build(self) -> PluginGroupBuilder {
        PluginGroupBuilder::start::<Self>()
            .add(HapticoPlugin)
            .add(CollettePlugin::default())
            .add(ForceCompPlugin::default())
    }
}

/// The device and the haptic thread (started in `PostStartup` with the [`HapticDevice`] resource, or a
/// simulated Phantom Desktop; stopped when the app exits), the [`HapticTool`] following it.
#[derive(Default)]
pub struct HapticoPlugin;

impl Plugin for HapticoPlugin {
    fn build(&self, app: &mut App) {
        // Colliders, effects and the volume are placed by their `GlobalTransform`s: a headless app
        // (`MinimalPlugins`) has no transform propagation of its own.
        if !app.is_plugin_added::<TransformPlugin>() {
            app.add_plugins(TransformPlugin);
        }
        if !app.world().contains_resource::<HapticDevice>() {
            app.init_resource::<HapticDevice>();
        }
        app.init_resource::<HapticDelegates>()
            .init_resource::<HapticStatus>()
            .init_resource::<HapticStats>()
            .init_resource::<HapticFrame>()
            .register_type::<HapticTool>()
            .register_type::<ForceComponent>()
            .register_type::<Ridges>()
            .register_type::<HapticEffect>()
            .register_type::<EffectKind>()
            .add_message::<ToolMoved>()
            .configure_sets(PreUpdate, HapticsSystems::Read)
            .configure_sets(PostUpdate, HapticsSystems::Write.after(TransformSystems::Propagate))
            .add_systems(PostStartup, runtime::start)
            .add_systems(PostUpdate, effects::sync_effects.in_set(HapticsSystems::Write))
            .add_systems(
                PreUpdate,
                (runtime::read_threads, runtime::follow_device).chain().in_set(HapticsSystems::Read),
            )
            .add_systems(Last, runtime::stop_on_exit);
    }
}

/// The collision thread (collette's pipeline at 1 kHz): sphere trees as assets (`.ist` files, `.obj`
/// meshes, a [`SphereTreeFromMesh`] beside a `Mesh3d`), [`HapticCollider`]s against the tool,
/// a [`CollisionVolume`], and contact messages and observer events.
#[derive(Default)]
pub struct CollettePlugin {
    /// The collision thread's rate, budget and pacing.
    pub collision: haptic_rig::CollisionConfig,
}

impl Plugin for CollettePlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(CollisionSettings(self.collision.clone()))
            .init_asset::<SphereTree>()
            .init_asset_loader::<SphereTreeLoader>()
            .register_type::<HapticCollider>()
            .register_type::<CollisionVolume>()
            .register_type::<CollisionWatcher>()
            .register_type::<HapticPushable>()
            .register_type::<SphereTreeFromMesh>()
            .register_type::<SphereTreeSource>()
            // A `Handle<SphereTree>` in a scene file (`tree: Path("trees/box.ist")`) loads that file.
            .register_type_data::<Handle<SphereTree>, ReflectHandle>()
            .register_type::<ContactData>()
            .add_message::<ContactStarted>()
            .add_message::<ContactOngoing>()
            .add_message::<ContactEnded>()
            .add_message::<PairContactStarted>()
            .add_message::<PairContactEnded>()
            .add_message::<ToolPushed>()
            .add_systems(
                PreUpdate,
                (runtime::report_contacts, runtime::report_pair_contacts, runtime::report_pushes)
                    .in_set(HapticsSystems::Read),
            )
            .add_systems(Update, (mesh_build::start_mesh_builds, mesh_build::finish_mesh_builds));
        #[cfg(feature = "avian3d")]
        app.add_systems(
            PreUpdate,
            crate::avian::apply_pushes.after(runtime::report_pushes).in_set(HapticsSystems::Read),
        );
        app.add_systems(
            PostUpdate,
            (
                source::load_sources.before(runtime::sync_tool).before(runtime::send_colliders),
                runtime::sync_tool,
                (runtime::forget_colliders, runtime::send_colliders, runtime::move_colliders, runtime::sync_watchers)
                    .chain(),
                runtime::sync_volume,
            )
                .in_set(HapticsSystems::Write),
        );
    }
}

/// Contact forces on the haptic thread (forcecomp): the paper's volumetric penalty (Eq. 1, 2) through a
/// virtual coupling, or the 3-DOF proxy; materials from [`ForceComponent`]s. Needs [`CollettePlugin`].
#[derive(Default)]
pub struct ForceCompPlugin {
    /// How contact forces are rendered (default: by the device).
    pub mode: RenderingMode,
    /// How the 3-DOF proxy feels materials.
    pub proxy: ProxyRendering,
    /// How [`HapticPushable`] objects follow your game's bodies: set its `latency_s` to how long your
    /// game takes to show a push in the poses it sends (default 45 ms: a 60 Hz game; 70 ms at 30 Hz).
    pub pushes: PushCoupling,
}

impl Plugin for ForceCompPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(ForceRendering { mode: self.mode, proxy: self.proxy, pushes: self.pushes });
    }
}
