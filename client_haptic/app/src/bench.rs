//! The Phantom client's haptics on `bevy_haptics`, as any Bevy game adds them: the device the settings
//! name, the stylus's gemstone as the `HapticTool`, the copy on the workbench as a `HapticCollider`
//! with its briefed material, and the loops' rates while a copy is felt.
//!
//! You need this module to feel a copy in the running client. [`add_haptics`] opens the device (its
//! errors are the command line's, before anything starts) and adds `HapticsPlugins` set up for copies
//! ([`RigSetup`]: the rendering, the proxy's spring and the workspace scale for the device).
//! [`Bench::place`] builds a copy's tree (and its surface grid with volumetric rendering) on the async
//! compute pool; once built, the copy becomes an entity the collision thread watches and [`CopyLanded`]
//! says so. Nothing here waits on the game thread. What a copy *is* (its tree, its material, the cache)
//! is [`crate::haptics`].

use std::path::PathBuf;

use bevy::asset::AssetPlugin;
use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, block_on, poll_once};
use bevy_haptics::{
    CollettePlugin, ForceCompPlugin, ForceComponent, HapticCollider, HapticDevice, HapticDeviceLink, HapticFrame,
    HapticStatus, HapticTool, HapticsPlugins, HapticsSystems, RenderingMode, SimulatedHand, SphereTree,
};
use collette::SignedDistanceGrid;
use haptic_rig::{ForceSample, Rendering, WorkspaceMap};
use heist_shared::protocol::{ItemId, WorkbenchCopy};

use crate::device::{self, HandGoal};
use crate::error::ClientError;
use crate::haptics::{
    Built, BuiltCopy, HapticsSettings, OnBench, RateWindow, RigSetup, build_copy, haptic_material, proxy_hard_above,
};

/// Length of a rate window, µs.
const WINDOW_US: u64 = 1_000_000;

/// Opens the device `settings` name and adds the haptics stack set up for copies: `HapticsPlugins`
/// (with an `AssetPlugin` if the app has none), the gemstone tool, the [`Bench`] and the [`LoopRates`].
/// The threads start with the app (`PostStartup`).
pub fn add_haptics(app: &mut App, settings: &HapticsSettings) -> Result<(), ClientError> {
    if let Some(path) = &settings.record {
        // bevy_haptics writes the trace once the threads start; a file that cannot be written is said
        // now, on one line, before anything starts.
        std::fs::File::create(path)
            .map_err(|e| ClientError::Device(format!("recording the device: trace file {}: {e}", path.display())))?;
    }
    let preset = device::preset(settings.preset.as_deref())?;
    let opened = device::open(&settings.device, preset)?;
    let specs = opened.device.specs().clone();
    let setup = RigSetup::new(&specs, settings)?;
    let mode = match setup.rendering {
        Rendering::Proxy => RenderingMode::Proxy,
        _ => RenderingMode::Volumetric,
    };
    if !app.is_plugin_added::<AssetPlugin>() {
        app.add_plugins(AssetPlugin::default());
    }
    app.insert_resource(HapticDevice {
        scale: setup.map.scale,
        realtime_priority: settings.realtime_priority,
        record: settings.record.clone(),
        ..HapticDevice::opened(opened)
    });
    app.add_plugins(
        HapticsPlugins.set(CollettePlugin { collision: setup.config.collision.clone() }).set(ForceCompPlugin {
            mode,
            proxy: setup.config.proxy,
            pushes: setup.config.pushes,
        }),
    );
    let gem = SphereTree { tree: setup.tool.tree.clone(), surface: None, shell: None };
    let gem = app.world_mut().resource_mut::<Assets<SphereTree>>().add(gem);
    app.world_mut().spawn((Name::new("stylus gemstone"), HapticTool::new(gem), ForceComponent::rigid_tool()));
    app.insert_resource(Bench::new(&setup, settings))
        .init_resource::<LoopRates>()
        .add_message::<CopyLanded>()
        .add_systems(PreUpdate, (land_copies, count_rates, stop_without_haptics).after(HapticsSystems::Read));
    Ok(())
}

/// The copy on the workbench: the one being built, the one being felt, and what the device's rendering
/// makes of copies.
#[derive(Resource)]
pub struct Bench {
    /// How forces are rendered (the choice resolved for the device).
    pub rendering: Rendering,
    /// With proxy rendering: every copy's stiffness is scaled by this to fit the device.
    pub stiffness_scale: f32,
    /// Device frame to scene (the workbench frame).
    pub map: WorkspaceMap,
    /// The gem's packed volume at the reference depth, m³ (see [`haptic_material`]).
    pub tool_reference_volume_m3: f32,
    spheres: usize,
    cache_dir: Option<PathBuf>,
    building: Option<Building>,
    /// The copy being felt.
    pub on_bench: Option<OnBench>,
    copy: Option<Entity>,
    to_despawn: Vec<Entity>,
}

/// A copy's tree being built.
struct Building {
    item: ItemId,
    task: Task<Built>,
    material: ForceComponent,
}

impl Bench {
    fn new(setup: &RigSetup, settings: &HapticsSettings) -> Self {
        Self {
            rendering: setup.rendering,
            stiffness_scale: setup.stiffness_scale,
            map: setup.map,
            tool_reference_volume_m3: setup.tool_reference_volume_m3,
            spheres: settings.spheres,
            cache_dir: settings.cache_dir.clone(),
            building: None,
            on_bench: None,
            copy: None,
            to_despawn: Vec::new(),
        }
    }

    /// Starts building the tree of `copy` (replacing whatever was on the bench), and its surface grid
    /// unless the proxy renders it (the proxy reads the tree's spheres alone).
    pub fn place(&mut self, copy: &WorkbenchCopy) {
        self.clear();
        let mesh = copy.mesh.clone();
        let (spheres, cache) = (self.spheres, self.cache_dir.clone());
        let with_surface = self.rendering != Rendering::Proxy;
        let task = AsyncComputeTaskPool::get()
            .spawn(async move { build_copy(&mesh, spheres, cache.as_deref(), with_surface) });
        let material = haptic_material(&copy.material, self.tool_reference_volume_m3);
        self.building = Some(Building { item: copy.item, task, material });
    }

    /// Takes the copy off the bench (its entity goes in the next `PreUpdate`).
    pub fn clear(&mut self) {
        self.building = None;
        self.on_bench = None;
        self.to_despawn.extend(self.copy.take());
    }

    /// Whether `item` is on the bench, ready to feel.
    pub fn holds(&self, item: ItemId) -> bool {
        self.on_bench.as_ref().is_some_and(|o| o.item == item)
    }

    /// With proxy rendering, the resting force over depth (N/m) above which a copy feels hard; `None`
    /// with volumetric rendering (the touch bot then judges by force over depth²).
    pub fn hard_above_n_per_m(&self) -> Option<f32> {
        proxy_hard_above(self.rendering, self.stiffness_scale)
    }
}

/// A copy's tree reached the collision thread, or could not be built (why).
#[derive(Message, Clone, Debug, PartialEq)]
pub struct CopyLanded {
    /// The copy.
    pub item: ItemId,
    /// What is on the bench, or why the copy cannot be felt.
    pub result: Result<OnBench, String>,
}

/// Spawns a built copy as a collider with its material; despawns the copies taken off (`PreUpdate`).
fn land_copies(
    mut bench: ResMut<Bench>,
    mut commands: Commands,
    mut trees: ResMut<Assets<SphereTree>>,
    frame: Res<HapticFrame>,
    mut landed: MessageWriter<CopyLanded>,
) {
    let bench = &mut *bench;
    for entity in bench.to_despawn.drain(..) {
        commands.entity(entity).despawn();
    }
    let Some(building) = bench.building.as_mut() else { return };
    let Some(built) = block_on(poll_once(&mut building.task)) else { return };
    let Some(Building { item, material, .. }) = bench.building.take() else { return };
    let result = built.map(|BuiltCopy { tree, cached, surface }| {
        let spheres = tree.spheres().len();
        let surface_bytes = surface.as_ref().map(SignedDistanceGrid::memory_bytes);
        let tree = surface.into_iter().fold(SphereTree::new(tree), SphereTree::with_surface);
        let collider = HapticCollider::new(trees.add(tree));
        let copy = (Name::new(format!("copy {}", item.0)), collider, material, Transform::IDENTITY);
        bench.copy = Some(commands.spawn(copy).id());
        let on = OnBench { item, since_us: frame.now_us, spheres, cached, surface_bytes };
        bench.on_bench = Some(on.clone());
        on
    });
    landed.write(CopyLanded { item, result });
}

/// One-second rate windows of both loops (the game's own record: whether a copy was on the bench).
#[derive(Resource, Debug, Default)]
pub struct LoopRates {
    window: Option<(u64, u32, u32, bool)>,
    /// Every complete window so far.
    pub rates: Vec<RateWindow>,
}

/// Closes rate windows from this frame's ticks and steps (`PreUpdate`).
fn count_rates(frame: Res<HapticFrame>, bench: Res<Bench>, mut rates: ResMut<LoopRates>) {
    let with_copy = bench.on_bench.is_some();
    let rates = &mut *rates;
    let ticks = frame.ticks.iter().map(|t| (t.start_us, true));
    for t in ticks.chain(frame.steps.iter().map(|s| (s.start_us, false))) {
        let w = rates.window.get_or_insert((t.0 - t.0 % WINDOW_US, 0, 0, with_copy));
        if t.0 >= w.0 + WINDOW_US {
            let done = RateWindow { start_us: w.0, haptic_hz: w.1, collision_hz: w.2, with_copy: w.3 };
            rates.rates.push(done);
            debug!(
                "haptic loop: {} Hz, collision {} Hz{}",
                done.haptic_hz,
                done.collision_hz,
                if done.with_copy { " (copy on the bench)" } else { "" }
            );
            *w = (t.0 - t.0 % WINDOW_US, 0, 0, with_copy);
        }
        if t.1 {
            w.1 += 1
        } else {
            w.2 += 1
        }
        w.3 &= with_copy;
    }
}

/// A client whose haptic threads could not start has nothing to play with: it exits (`bevy_haptics`
/// logged why).
fn stop_without_haptics(status: Res<HapticStatus>, mut exit: MessageWriter<AppExit>) {
    if status.is_changed() && matches!(*status, HapticStatus::Failed(_)) {
        exit.write(AppExit::error());
    }
}

/// The haptic side as the client's systems see it: the bench, the threads' latest frame, the simulated
/// hand (sim device) and the device's link.
#[derive(SystemParam)]
pub struct Haptics<'w> {
    /// The copy on the bench.
    pub bench: ResMut<'w, Bench>,
    /// What the threads did since the last frame.
    pub frame: Res<'w, HapticFrame>,
    /// The simulated hand (sim device only).
    pub hand: Option<ResMut<'w, SimulatedHand>>,
    link: Option<Res<'w, HapticDeviceLink>>,
}

impl Haptics<'_> {
    /// Microseconds on the haptic clock.
    pub fn now_us(&self) -> u64 {
        self.hand.as_ref().map_or(self.frame.now_us, |h| h.now_us())
    }

    /// Where the stylus's tip is, in the scene (the workbench's) frame.
    pub fn stylus(&self) -> Vec3 {
        stylus(&self.bench.map, &self.frame)
    }

    /// Every tick's force since the last frame.
    pub fn samples(&self) -> &[ForceSample] {
        &self.frame.samples
    }

    /// Sends the simulated hand after `goal` (scene frame); nothing without a simulated hand.
    pub fn steer(&mut self, goal: HandGoal) {
        let map = self.bench.map;
        if let Some(hand) = self.hand.as_mut() {
            hand.set(device::to_device(&map, goal));
        }
    }

    /// What the device's link and the safety layer say now, for the [`device::Guide`].
    pub fn device_reading(&self) -> device::Reading {
        let link = self.link.as_ref().map_or_else(device::Reading::default, |l| device::reading(&l.0));
        device::Reading { outside_workspace: self.frame.outside_workspace, ..link }
    }
}

/// Where the stylus's tip is in `frame`, in the scene frame of `map`.
pub fn stylus(map: &WorkspaceMap, frame: &HapticFrame) -> Vec3 {
    map.to_scene(&frame.device.pose).translation
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trace_that_cannot_be_written_is_refused_before_anything_starts() {
        let record = Some(PathBuf::from("/nonexistent-dir/trace.csv"));
        let mut app = App::new();
        let err = add_haptics(&mut app, &HapticsSettings { record, ..HapticsSettings::default() })
            .expect_err("no such directory");
        let line = err.to_string();
        assert!(line.contains("recording the device: trace file /nonexistent-dir/trace.csv"), "{line}");
        assert!(!line.contains('\n'), "one line: {line}");
        assert!(app.world().get_resource::<Bench>().is_none(), "nothing was set up");
    }
}
