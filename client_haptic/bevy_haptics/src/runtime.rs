//! The running threads and the systems that keep them and the world in step: the tool's `Transform`
//! from the device, colliders' trees, poses and materials to the collision and haptic threads, contacts
//! back as messages and observer events, the loop's figures.
//!
//! You need this module to see what happens each frame (the plugins add these systems): in `PreUpdate`
//! the tool moves and contacts are reported, in `PostUpdate` (after transforms propagate) what the game
//! changed reaches the threads, in `Last` an exiting app stops them.

use std::collections::{HashMap, HashSet};
use std::sync::{Arc, Mutex};

use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use forcecomp::SafetyLayer;
use haptic_common::{ForceOnHapticTick, Pose};
use haptic_rig::{ForceSample, HapticRig, ObjectSpec, Rendering, RigConfig, ToolSpec};
use haptico::trace::TraceWriter;
use haptico::{Device, DeviceSpecs, HapticClock, HapticEvents, HapticHandle};

use crate::components::{
    CollisionVolume, CollisionWatcher, ForceComponent, HapticCollider, HapticPushable, HapticTool,
};
use crate::device::{HapticDevice, HapticDeviceLink, SimulatedHand};
use crate::events::{
    ContactData, ContactEnded, ContactOngoing, ContactStarted, PairContactEnded, PairContactStarted, ToolMoved,
    ToolPushed,
};
use crate::frame::HapticFrame;
use crate::settings::{CollisionSettings, ForceRendering};
use crate::stats::HapticStats;
use crate::tree::SphereTree;

/// Delegates to bind to the haptic thread's events before it starts (the paper's OnTransform and
/// ForceOnHapticTick, run at 1 kHz on the haptic thread). Bind them while building the app or in a
/// `Startup` system; the threads start in `PostStartup` and take them.
///
/// A force delegate adds its force and torque (device frame, N and N·m) to the tick; with
/// `ForceCompPlugin` the contact forces are added after yours, and the safety layer always has the last
/// word. Delegates run on the haptic thread: they must not allocate, lock, block or log.
#[derive(Resource, Default)]
pub struct HapticDelegates {
    // A mutex only to make the resource `Sync` (delegates are `Send`): it is locked while binding.
    events: Mutex<Option<HapticEvents>>,
}

impl HapticDelegates {
    fn bind(&mut self, f: impl FnOnce(&mut HapticEvents)) {
        let events = self.events.get_mut().unwrap_or_else(|p| p.into_inner());
        f(events.get_or_insert_with(HapticEvents::default));
    }

    fn take(&mut self) -> HapticEvents {
        self.events.get_mut().unwrap_or_else(|p| p.into_inner()).take().unwrap_or_default()
    }

    /// Binds `delegate` to ForceOnHapticTick.
    pub fn force_on_haptic_tick(&mut self, delegate: impl FnMut(&ForceOnHapticTick) + Send + 'static) {
        self.bind(|e| {
            e.force_on_haptic_tick.add_delegate(delegate);
        });
    }

    /// Binds `delegate` to OnTransform (the device's state, every tick, before the forces).
    pub fn on_transform(&mut self, delegate: impl FnMut(&haptic_common::DeviceState) + Send + 'static) {
        self.bind(|e| {
            e.on_transform.add_delegate(delegate);
        });
    }
}

/// Whether the haptic threads run.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub enum HapticStatus {
    /// Not started yet (before `PostStartup`).
    #[default]
    Starting,
    /// Running, with the device's limits and the rendering in use.
    Running {
        /// The device's name.
        device: &'static str,
        /// The largest force it renders, N.
        peak_force_n: f32,
        /// Whether it renders torque.
        torque: bool,
        /// How contact forces are rendered (`Off` without `ForceCompPlugin`).
        rendering: Rendering,
    },
    /// It could not start: why.
    Failed(String),
    /// Stopped with the app.
    Stopped,
}

/// The haptic thread alone (no collision), or the whole rig.
enum Engine {
    Device { handle: HapticHandle<Box<dyn Device>>, samples: rtrb::Consumer<ForceSample> },
    Rig(Box<HapticRig<Box<dyn Device>>>),
}

/// The running threads (the game thread's end).
#[derive(Resource)]
pub(crate) struct HapticRuntime {
    engine: Mutex<Engine>,
    map: haptic_rig::WorkspaceMap,
    /// Writes the recorded ticks ([`HapticDevice::record`]); declared after the engine, so that it is
    /// dropped after the haptic thread stopped and writes every tick.
    recording: Option<TraceWriter>,
    /// Ticks the recording had lost when last told.
    recording_lost: u64,
}

impl HapticRuntime {
    fn engine(&self) -> std::sync::MutexGuard<'_, Engine> {
        self.engine.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn rig<T>(&self, f: impl FnOnce(&HapticRig<Box<dyn Device>>) -> T) -> Option<T> {
        match &*self.engine() {
            Engine::Rig(rig) => Some(f(rig)),
            Engine::Device { .. } => None,
        }
    }
}

/// The game thread's record of what the threads watch: collider entities and their ids there.
#[derive(Resource, Default)]
pub(crate) struct Watched {
    ids: HashMap<Entity, u32>,
    entities: HashMap<u32, Entity>,
    next_id: u32,
    touching: HashSet<u32>,
    /// Watchers between two colliders on the threads: the pair's ids and entities.
    pairs: HashMap<Entity, WatchedPair>,
    /// The watchers whose pair overlaps.
    pairs_touching: HashSet<Entity>,
    tool: Option<ToolKey>,
    region: Option<(Vec3, Vec3)>,
}

/// A watcher's pair as the threads know it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct WatchedPair {
    ids: (u32, u32),
    entities: (Entity, Entity),
}

impl WatchedPair {
    fn joins(&self, id: u32) -> bool {
        self.ids.0 == id || self.ids.1 == id
    }
}

/// Opens the device and starts the threads (`PostStartup`).
pub(crate) fn start(world: &mut World) {
    let status = match try_start(world) {
        Ok(status) => status,
        Err(reason) => {
            error!("haptics did not start: {reason}");
            HapticStatus::Failed(reason)
        }
    };
    world.insert_resource(status);
}

fn try_start(world: &mut World) -> Result<HapticStatus, String> {
    let user = world.get_resource_mut::<HapticDelegates>().map(|mut d| d.take()).unwrap_or_default();
    let device = world.get_resource::<HapticDevice>().ok_or("no HapticDevice resource")?;
    let haptico::choice::Opened { device: opened, hand, link } = device.kind.open().map_err(|e| e.to_string())?;
    let (opened, recording): (Box<dyn Device>, _) = match &device.record {
        Some(path) => {
            let (recorded, writer) =
                haptico::trace::record(opened, path).map_err(|e| format!("recording the device: {e}"))?;
            (Box::new(recorded), Some(writer))
        }
        None => (opened, None),
    };
    let specs: DeviceSpecs = opened.specs().clone();
    let workspace = workspace_of(&link, &specs);
    let map = device.map();
    // Your delegates, then the effects (the force stage and the safety layer come after both).
    let (effects, run_effects) = crate::effects::delegate(map);
    let mut events = user;
    events.force_on_haptic_tick.add_delegate(run_effects);
    let haptic = haptico::HapticConfig {
        rate_hz: device.rate_hz,
        realtime_priority: device.realtime_priority,
        ..Default::default()
    };
    let rate_hz = haptic.rate_hz;
    let collision = world.get_resource::<CollisionSettings>().cloned();
    let force = world.get_resource::<ForceRendering>().copied();
    let rendering = force.map(|r| r.resolve(&specs));
    let pushes = force.map(|r| r.pushes).unwrap_or_default();
    let clock = HapticClock::new();
    let (engine, rendering, clock) = match collision {
        None => {
            let (handle, samples) = start_device(opened, events, haptic, &specs, workspace, clock)?;
            let clock = handle.clock();
            (Engine::Device { handle, samples }, Rendering::Off, clock)
        }
        Some(CollisionSettings(mut collision)) => {
            collision.realtime_priority = device.realtime_priority.map(|p| (p - 1).max(1));
            let (rendering, proxy) = rendering.unwrap_or((Rendering::Off, Default::default()));
            let config =
                RigConfig { haptic, collision, map, rendering, proxy, workspace, pushes, ..RigConfig::default() };
            let tool = ToolSpec::new(SphereTree::ball(HapticTool::default().tip_radius_m).tree, rigid_tool());
            let rig = HapticRig::start(opened, tool, config, events, Default::default()).map_err(|e| e.to_string())?;
            let clock = rig.clock();
            (Engine::Rig(Box::new(rig)), rendering, clock)
        }
    };
    if let Some(hand) = hand {
        world.insert_resource(SimulatedHand::new(hand, clock));
    }
    world.insert_resource(HapticDeviceLink(link));
    world.insert_resource(HapticRuntime { engine: Mutex::new(engine), map, recording, recording_lost: 0 });
    world.insert_resource(HapticFrame::with_capacity(1 << 12));
    world.init_resource::<Watched>();
    world.insert_resource(effects);
    info!("haptics: {} at {rate_hz} Hz, {rendering:?} rendering", specs.name);
    Ok(HapticStatus::Running {
        device: specs.name,
        peak_force_n: specs.peak_force_n,
        torque: specs.renders_torque(),
        rendering,
    })
}

/// Where a real device's grip must be read for forces to engage: the ball of its published workspace
/// around the device frame's origin (the Falcon's centre of travel, where an Inverse3 was centred).
/// `None` for devices without a link to lose (simulated, replayed, HID), whose grip goes where the
/// program puts it.
fn workspace_of(link: &haptico::DeviceLink, specs: &DeviceSpecs) -> Option<forcecomp::Workspace> {
    let real = !matches!(link, haptico::DeviceLink::Local);
    (real && specs.workspace_radius_m > 0.0)
        .then_some(forcecomp::Workspace { centre: Vec3::ZERO, radius_m: specs.workspace_radius_m })
}

fn rigid_tool() -> forcecomp::Material {
    ForceComponent::rigid_tool().material()
}

/// The haptic thread alone, and the ring of the forces it sent.
type DeviceOnly = (HapticHandle<Box<dyn Device>>, rtrb::Consumer<ForceSample>);

/// The haptic thread alone: your force delegates, then the safety layer (the device's limits), and a
/// ring of the forces sent for [`HapticStats`].
fn start_device(
    device: Box<dyn Device>,
    mut events: HapticEvents,
    config: haptico::HapticConfig,
    specs: &DeviceSpecs,
    workspace: Option<forcecomp::Workspace>,
    clock: HapticClock,
) -> Result<DeviceOnly, String> {
    let safety = forcecomp::SafetyConfig { workspace, ..haptic_rig::safety_for(specs) };
    safety.validate().map_err(|e| e.to_string())?;
    let mut safety = SafetyLayer::new(safety);
    let (mut samples_in, samples_out) = rtrb::RingBuffer::new(1 << 16);
    events.force_on_haptic_tick.add_delegate(move |tick: &ForceOnHapticTick| {
        let out = safety.apply_at(tick.total(), tick.dt_s, 0.0, tick.device.pose.translation);
        tick.set(out);
        let sample =
            ForceSample { t_us: tick.device.timestamp_us, force: out.force, torque: out.torque, ..Default::default() };
        let _ = samples_in.push(sample);
    });
    let handle = HapticHandle::spawn(device, events, config, clock).map_err(|e| e.to_string())?;
    Ok((handle, samples_out))
}

/// Stops the threads when the app exits (`Last`).
pub(crate) fn stop_on_exit(mut commands: Commands, mut exit: MessageReader<AppExit>, mut status: ResMut<HapticStatus>) {
    if exit.read().next().is_some() {
        commands.remove_resource::<HapticRuntime>();
        commands.remove_resource::<SimulatedHand>();
        commands.remove_resource::<crate::effects::EffectsInput>();
        if matches!(*status, HapticStatus::Running { .. }) {
            *status = HapticStatus::Stopped;
        }
    }
}

/// Reads the threads into [`HapticFrame`]: their latest state, and every tick's and step's timing and
/// force since the last frame; adds them to [`HapticStats`] (`PreUpdate`).
pub(crate) fn read_threads(
    runtime: Option<ResMut<HapticRuntime>>,
    frame: Option<ResMut<HapticFrame>>,
    mut stats: ResMut<HapticStats>,
) {
    let (Some(mut runtime), Some(mut frame)) = (runtime, frame) else { return };
    let (runtime, frame) = (&mut *runtime, &mut *frame);
    frame.ticks.clear();
    frame.steps.clear();
    frame.samples.clear();
    match &mut *runtime.engine.lock().unwrap_or_else(|p| p.into_inner()) {
        Engine::Rig(rig) => {
            let t = rig.telemetry();
            (frame.device, frame.tool, frame.output) = (t.device, t.tool_pose, t.output);
            frame.outside_workspace = t.outside_workspace;
            frame.now_us = rig.clock().now_us();
            rig.drain_haptic_timings(&mut frame.ticks);
            rig.drain_collision_timings(&mut frame.steps);
            rig.drain_force_samples(&mut frame.samples);
            rig.collect_garbage();
        }
        Engine::Device { handle, samples } => {
            let t = handle.telemetry();
            (frame.device, frame.tool, frame.output) = (t.device, runtime.map.to_scene(&t.device.pose), t.command);
            frame.outside_workspace = false;
            frame.now_us = handle.clock().now_us();
            handle.drain_timings(&mut frame.ticks);
            while let Ok(s) = samples.pop() {
                frame.samples.push(s);
            }
            handle.collect_garbage();
        }
    }
    if let Some(writer) = &runtime.recording
        && writer.dropped() > runtime.recording_lost
    {
        runtime.recording_lost = writer.dropped();
        warn!("the trace {} has lost {} ticks: the disk is too slow", writer.path().display(), runtime.recording_lost);
    }
    for t in &frame.ticks {
        stats.haptic.record(t.start_us);
    }
    for s in &frame.steps {
        stats.collision.record(s.start_us);
    }
    for s in &frame.samples {
        stats.record_force_at(s.t_us, s.force, s.torque);
    }
}

/// Moves the tool to where the threads have it and tells the game (`PreUpdate`, after [`read_threads`]).
pub(crate) fn follow_device(
    frame: Option<Res<HapticFrame>>,
    mut tools: Query<(Entity, &mut Transform), With<HapticTool>>,
    mut moved: MessageWriter<ToolMoved>,
    mut commands: Commands,
) {
    let Some(frame) = frame else { return };
    for (tool, mut transform) in &mut tools {
        transform.translation = frame.tool.translation;
        transform.rotation = frame.tool.rotation;
        let event =
            ToolMoved { tool, transform: *transform, force_n: frame.output.force, torque_nm: frame.output.torque };
        moved.write(event);
        commands.trigger(event);
    }
}

/// What the tool was last sent as: its tree (or its ball's radius) and material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ToolKey {
    tree: Option<AssetId<SphereTree>>,
    tip_radius_m: f32,
    material: Option<ForceComponent>,
}

/// Sends the tool's tree and material when they change (`PostUpdate`).
pub(crate) fn sync_tool(
    mut threads: Threads,
    trees: Res<Assets<SphereTree>>,
    tools: Query<(&HapticTool, Option<&ForceComponent>)>,
) {
    let Some((runtime, watched)) = threads.get() else { return };
    let Some((tool, force)) = tools.iter().next() else { return };
    let tree = tool.tree.as_ref().and_then(|h| trees.get(h).map(|t| (h.id(), t)));
    let key = ToolKey { tree: tree.map(|(id, _)| id), tip_radius_m: tool.tip_radius_m, material: force.copied() };
    if watched.tool == Some(key) {
        return;
    }
    let (tree, shell, surface) = tree.map_or_else(
        || (SphereTree::ball(tool.tip_radius_m).tree, None, None),
        |(_, t)| (t.tree.clone(), t.shell.clone(), t.surface.clone()),
    );
    let mut spec = ToolSpec::new(tree, key.material.map_or_else(rigid_tool, |m| m.material()));
    // The tool's grid matters with its shell: both surfaces against a collider that has both.
    if let Some(shell) = shell {
        spec = spec.with_shell(shell);
        if let Some(surface) = surface {
            spec = spec.with_surface(surface);
        }
    }
    match runtime.rig(|rig| rig.set_tool(spec)) {
        Some(Err(e)) => warn!("the tool's tree waits: {e}"),
        _ => watched.tool = Some(key),
    }
}

type ColliderChanged =
    Or<(Changed<HapticCollider>, Changed<ForceComponent>, Added<HapticCollider>, Changed<HapticPushable>)>;
type ColliderMoved = (With<HapticCollider>, Changed<GlobalTransform>);
type Collider<'a> =
    (Entity, &'a HapticCollider, &'a GlobalTransform, Option<&'a ForceComponent>, Option<&'a HapticPushable>);

/// The game thread's two ends: the threads (if running) and its record of what they watch.
#[derive(SystemParam)]
pub(crate) struct Threads<'w> {
    runtime: Option<Res<'w, HapticRuntime>>,
    watched: Option<ResMut<'w, Watched>>,
}

impl Threads<'_> {
    fn get(&mut self) -> Option<(&HapticRuntime, &mut Watched)> {
        Some((self.runtime.as_deref()?, self.watched.as_deref_mut()?))
    }
}

/// What tells the game of contacts: the three messages and the observers.
#[derive(SystemParam)]
pub(crate) struct ContactWriters<'w, 's> {
    started: MessageWriter<'w, ContactStarted>,
    ongoing: MessageWriter<'w, ContactOngoing>,
    ended: MessageWriter<'w, ContactEnded>,
    commands: Commands<'w, 's>,
}

/// What tells the game of watched pairs: the two messages and the observers.
#[derive(SystemParam)]
pub(crate) struct PairWriters<'w, 's> {
    started: MessageWriter<'w, PairContactStarted>,
    ended: MessageWriter<'w, PairContactEnded>,
    commands: Commands<'w, 's>,
}

impl PairWriters<'_, '_> {
    fn ended(&mut self, watcher: Entity, pair: WatchedPair) {
        let event = PairContactEnded { watcher, a: pair.entities.0, b: pair.entities.1 };
        self.ended.write(event);
        if self.commands.get_entity(watcher).is_ok() {
            self.commands.trigger(event);
        }
    }
}

impl ContactWriters<'_, '_> {
    fn ended(&mut self, object: Entity, tool: Entity) {
        let event = ContactEnded { object, tool };
        self.ended.write(event);
        // A despawned object has no observers of its own left (the global ones heard the message).
        if self.commands.get_entity(object).is_ok() {
            self.commands.trigger(event);
        }
    }
}

/// Takes colliders that lost their component (or their entity) off the threads, ending their contacts
/// (`PostUpdate`).
pub(crate) fn forget_colliders(
    mut threads: Threads,
    mut removed: RemovedComponents<HapticCollider>,
    tools: Query<Entity, With<HapticTool>>,
    mut writers: ContactWriters,
    mut pair_writers: PairWriters,
) {
    let Some((runtime, watched)) = threads.get() else { return };
    let tool = tools.iter().next().unwrap_or(Entity::PLACEHOLDER);
    for entity in removed.read() {
        let Some(id) = watched.ids.remove(&entity) else { continue };
        // The rig ends the object's watchers with it; they start again if it comes back.
        let ended: Vec<_> = watched.pairs.iter().filter(|(_, p)| p.joins(id)).map(|(w, p)| (*w, *p)).collect();
        for (watcher, pair) in ended {
            watched.pairs.remove(&watcher);
            if watched.pairs_touching.remove(&watcher) {
                pair_writers.ended(watcher, pair);
            }
        }
        watched.entities.remove(&id);
        if let Some(Err(e)) = runtime.rig(|rig| rig.remove_object(id)) {
            warn!("removing {entity} from the collision thread: {e}");
        }
        if watched.touching.remove(&id) {
            writers.ended(entity, tool);
        }
    }
}

/// Sends new colliders, and those whose tree or material changed, once their tree is loaded
/// (`PostUpdate`, after transforms).
pub(crate) fn send_colliders(
    mut threads: Threads,
    trees: Res<Assets<SphereTree>>,
    changed: Query<Entity, ColliderChanged>,
    all: Query<Collider>,
) {
    let Some((runtime, watched)) = threads.get() else { return };
    // A collider whose tree is still loading is sent once it is there (checked every frame).
    let waiting = all.iter().map(|(e, ..)| e).filter(|e| !watched.ids.contains_key(e));
    let to_send: HashSet<Entity> = changed.iter().chain(waiting).collect();
    for (entity, collider, transform, force, pushable) in to_send.into_iter().filter_map(|e| all.get(e).ok()) {
        let Some(tree) = trees.get(&collider.tree) else { continue };
        let id = match watched.ids.get(&entity) {
            Some(&id) => id,
            None => {
                watched.next_id += 1;
                watched.next_id
            }
        };
        let material = force.copied().unwrap_or_default().material();
        let spec = ObjectSpec { id, tree: Arc::clone(&tree.tree), pose: pose_of(transform), material };
        let (surface, shell) = (tree.surface.clone(), tree.shell.clone());
        let added = runtime.rig(|rig| {
            match pushable {
                Some(p) => rig.add_pushable(spec, p.mass_kg),
                None => rig.add_object(spec),
            }
            .and_then(|()| rig.set_surface(id, surface))
            .and_then(|()| rig.set_object_shell(id, shell))
        });
        match added {
            Some(Err(e @ haptic_rig::RigError::BadMass { .. })) => {
                // Not a queue to wait for: said once, and the entity is not sent again until it changes.
                warn!("{entity} is not pushable: {e}");
                watched.ids.insert(entity, id);
            }
            Some(Err(e)) => warn!("{entity} waits for the collision thread: {e}"),
            _ => {
                watched.ids.insert(entity, id);
                watched.entities.insert(id, entity);
            }
        }
    }
}

/// Starts the watchers between two colliders once both are on the threads, and stops those that went
/// (`PostUpdate`, after the colliders are sent).
pub(crate) fn sync_watchers(
    mut threads: Threads,
    watchers: Query<(Entity, &CollisionWatcher)>,
    mut removed: RemovedComponents<CollisionWatcher>,
    mut writers: PairWriters,
) {
    let Some((runtime, watched)) = threads.get() else { return };
    for watcher in removed.read() {
        let Some(pair) = watched.pairs.remove(&watcher) else { continue };
        if let Some(Err(e)) = runtime.rig(|rig| rig.unwatch_pair(pair.ids.0, pair.ids.1)) {
            warn!("stopping the watcher {watcher}: {e}");
        }
        if watched.pairs_touching.remove(&watcher) {
            writers.ended(watcher, pair);
        }
    }
    for (watcher, w) in &watchers {
        // A watcher waits until both its colliders are on the threads.
        let (Some(&a), Some(&b)) = (watched.ids.get(&w.a), watched.ids.get(&w.b)) else { continue };
        let pair = WatchedPair { ids: (a, b), entities: (w.a, w.b) };
        if watched.pairs.get(&watcher) == Some(&pair) {
            continue;
        }
        if let Some(old) = watched.pairs.remove(&watcher)
            && let Some(Err(e)) = runtime.rig(|rig| rig.unwatch_pair(old.ids.0, old.ids.1))
        {
            warn!("moving the watcher {watcher} to another pair: {e}");
        }
        match runtime.rig(|rig| rig.watch_pair(a, b)) {
            Some(Err(e)) => warn!("the watcher {watcher} waits: {e}"),
            _ => {
                watched.pairs.insert(watcher, pair);
            }
        }
    }
}

/// Reports watched pairs starting and ending to overlap (`PreUpdate`).
pub(crate) fn report_pair_contacts(
    mut threads: Threads,
    mut latest: Local<Vec<haptic_rig::PairContact>>,
    mut writers: PairWriters,
) {
    let Some((runtime, watched)) = threads.get() else { return };
    latest.clear();
    runtime.rig(|rig| rig.pair_contacts(&mut latest));
    for (&watcher, &pair) in &watched.pairs {
        let (a, b) = pair.ids;
        let now = latest.iter().find(|p| p.touching && ((p.a, p.b) == (a, b) || (p.a, p.b) == (b, a)));
        match (now, watched.pairs_touching.contains(&watcher)) {
            (Some(p), false) => {
                watched.pairs_touching.insert(watcher);
                let (a, b) = pair.entities;
                let event = PairContactStarted { watcher, a, b, volume_m3: p.volume_m3, pairs: p.pairs };
                writers.started.write(event);
                writers.commands.trigger(event);
            }
            (None, true) => {
                watched.pairs_touching.remove(&watcher);
                writers.ended(watcher, pair);
            }
            _ => {}
        }
    }
}

/// Moves colliders the game moved (`PostUpdate`, after transforms): each new pose goes to the threads
/// with the time it was sent on the haptic clock, so they move the collider smoothly between frames and
/// feel its velocity (`haptic_rig`'s pose tracks, read 20 ms behind); one the game stops moving rests
/// at its last pose.
pub(crate) fn move_colliders(mut threads: Threads, moved: Query<(Entity, &GlobalTransform), ColliderMoved>) {
    let Some((runtime, watched)) = threads.get() else { return };
    for (entity, transform) in &moved {
        // Only colliders on the threads (one refused for its mass has an id but is not there).
        let Some(&id) = watched.ids.get(&entity).filter(|id| watched.entities.contains_key(id)) else { continue };
        let sent = runtime.rig(|rig| rig.set_object_pose_at(id, pose_of(transform), rig.clock().now_us()));
        if let Some(Err(e)) = sent {
            warn!("moving {entity} on the collision thread: {e}");
        }
    }
}

fn pose_of(transform: &GlobalTransform) -> Pose {
    let (_, rotation, translation) = transform.to_scale_rotation_translation();
    Pose::new(translation, rotation)
}

/// Hands what the tool did to pushed objects to the game (`PreUpdate`): one [`ToolPushed`] per object,
/// as a message and triggered on the object.
pub(crate) fn report_pushes(
    mut threads: Threads,
    mut pushes: Local<Vec<haptic_rig::ObjectPush>>,
    mut pushed: MessageWriter<ToolPushed>,
    mut commands: Commands,
) {
    let Some((runtime, watched)) = threads.get() else { return };
    pushes.clear();
    runtime.rig(|rig| rig.take_pushes(&mut pushes));
    for p in pushes.iter() {
        let Some(&object) = watched.entities.get(&p.id) else { continue };
        let duration_s = p.to_us.saturating_sub(p.from_us) as f32 * 1e-6;
        let event =
            ToolPushed { object, impulse_ns: p.impulse_ns, angular_impulse_nms: p.angular_impulse_nms, duration_s };
        pushed.write(event);
        if commands.get_entity(object).is_ok() {
            commands.trigger(event);
        }
    }
}

/// Sends the collision volume's box when it changes or goes (`PostUpdate`).
pub(crate) fn sync_volume(mut threads: Threads, volumes: Query<(&CollisionVolume, &GlobalTransform)>) {
    let Some((runtime, watched)) = threads.get() else { return };
    let region = volumes.iter().next().map(|(v, t)| {
        let c = t.translation();
        let h = v.half_extents_m.abs();
        (c - h, c + h)
    });
    if region == watched.region {
        return;
    }
    let aabb = region.map(|(min, max)| collette::bounding_volume::Aabb::new(min, max));
    if let Some(Ok(())) = runtime.rig(|rig| rig.set_region(aabb)) {
        watched.region = region;
    }
}

/// Reports contacts starting, going on and ending (`PreUpdate`).
pub(crate) fn report_contacts(
    mut threads: Threads,
    tools: Query<Entity, With<HapticTool>>,
    mut writers: ContactWriters,
    mut stats: ResMut<HapticStats>,
) {
    let Some((runtime, watched)) = threads.get() else { return };
    let Some(telemetry) = runtime.rig(|rig| rig.telemetry()) else { return };
    let tool = tools.iter().next().unwrap_or(Entity::PLACEHOLDER);
    let mut now = HashSet::new();
    for c in telemetry.objects().iter().filter(|c| c.touching) {
        let Some(&object) = watched.entities.get(&c.id) else { continue };
        now.insert(c.id);
        let contact = ContactData { pairs: c.contacts, volume_m3: c.volume, force_n: c.force, torque_nm: c.torque };
        if watched.touching.contains(&c.id) {
            let event = ContactOngoing { object, tool, contact };
            writers.ongoing.write(event);
            writers.commands.trigger(event);
        } else {
            stats.contacts_started += 1;
            let event = ContactStarted { object, tool, contact };
            writers.started.write(event);
            writers.commands.trigger(event);
        }
    }
    for id in watched.touching.difference(&now) {
        if let Some(&object) = watched.entities.get(id) {
            writers.ended(object, tool);
        }
    }
    watched.touching = now;
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use haptico::DeviceLink;

    use super::*;

    #[test]
    fn real_devices_keep_forces_to_their_published_workspace_and_programs_steer_anywhere() {
        let w =
            workspace_of(&DeviceLink::Falcon(Arc::default()), &haptico::presets::falcon()).expect("a Falcon has one");
        assert_eq!((w.centre, w.radius_m), (Vec3::ZERO, 0.04));
        let inverse3 = haptico::presets::inverse3();
        let haply = workspace_of(&DeviceLink::Haply(Arc::default()), &inverse3).expect("an Inverse3 has one");
        // Where the Phantom client puts the grip (in front of its workbench) is inside the Inverse3's reach.
        assert!(haply.holds(Vec3::new(0.0, 0.06, 0.07)), "{haply:?}");
        assert_eq!(workspace_of(&DeviceLink::Local, &haptico::presets::phantom_desktop()), None);
    }
}
