//! The assembled loop and the control handle the game thread uses (the paper's EventHandler).
//!
//! You need this module to run the full stack: device → OnTransform / ForceOnHapticTick (haptic thread)
//! → tool pose → collision thread (collette's pipeline) → contacts → force stage (forcecomp) → device.

use std::sync::Mutex;

use collette::pipeline::{CollisionHandle, CollisionThread, TrackTiming};
use forcecomp::{CouplingConfig, GodObject, SafetyConfig, SafetyLayer, VirtualCoupling, Workspace};
use haptic_common::{Delegator, OnCollision, Pose};
use haptico::{Device, HapticClock, HapticConfig, HapticEvents, HapticHandle, HapticTelemetry, TickTiming};

use crate::collision::{CollisionConfig, RigPacer, StepTiming};
use crate::force::{ForceSample, ForceStage, ProxyRendering, Rendering, RigTelemetry, SceneInput};
use crate::push::{ObjectPush, PushCoupling};
use crate::scene::{FORCE_COMMANDS, Scene};
use crate::spec::{MAX_OBJECTS, ObjectSpec, PairContact, ToolSpec};
use crate::{Result, RigError, WorkspaceMap};

/// Settings of the whole rig.
#[derive(Clone, Debug, PartialEq)]
pub struct RigConfig {
    /// The haptic thread.
    pub haptic: HapticConfig,
    /// The collision thread.
    pub collision: CollisionConfig,
    /// Device frame to scene.
    pub map: WorkspaceMap,
    /// Coupling (None: derived from the device's limits and a 4 N·s/m hand).
    pub coupling: Option<CouplingConfig>,
    /// Safety limits (None: the device's peak force and torque, heating down to its continuous force,
    /// with the default habits).
    pub safety: Option<SafetyConfig>,
    /// Where the grip must be read for forces to engage (device frame; see [`Workspace`]), whatever
    /// `safety` says; None: anywhere. A real device's client sets it from the device's workspace.
    pub workspace: Option<Workspace>,
    /// Coupled, direct or 3-DOF proxy rendering (default coupled).
    pub rendering: Rendering,
    /// How the 3-DOF proxy feels materials (with `Rendering::Proxy`).
    pub proxy: ProxyRendering,
    /// Capacity of the per-tick force-sample ring (default 65 536).
    pub force_sample_capacity: usize,
    /// How the tracks of objects the game moves are read (see
    /// [`set_object_pose_at`](HapticRig::set_object_pose_at)): by default 20 ms behind, which suits a
    /// game sending poses at 60 Hz or faster.
    pub tracks: TrackTiming,
    /// How objects the tool pushes follow the game's bodies ([`HapticRig::add_pushable`]).
    pub pushes: PushCoupling,
}

impl Default for RigConfig {
    fn default() -> Self {
        Self {
            haptic: HapticConfig::default(),
            collision: CollisionConfig::default(),
            map: WorkspaceMap::default(),
            coupling: None,
            safety: None,
            workspace: None,
            rendering: Rendering::Coupled,
            proxy: ProxyRendering::default(),
            force_sample_capacity: 1 << 16,
            tracks: TrackTiming::default(),
            pushes: PushCoupling::default(),
        }
    }
}

/// The safety layer's settings for a device: its peak force and torque, heating down to its continuous
/// force, with the default habits (what a [`RigConfig`] without `safety` uses).
pub fn safety_for(specs: &haptico::DeviceSpecs) -> SafetyConfig {
    SafetyConfig::for_limits(specs.peak_force_n, specs.max_torque_nm).with_continuous_force(specs.continuous_force_n)
}

/// What the game thread reads back from the force stage.
pub(crate) struct Outputs {
    pub(crate) samples: rtrb::Consumer<ForceSample>,
    pub(crate) telemetry: triple_buffer::Output<RigTelemetry>,
    pub(crate) pushes: rtrb::Consumer<ObjectPush>,
}

impl Outputs {
    /// Moves what the tool did to pushed objects into `out`, one entry per object (merged with any
    /// entry for it already there).
    pub(crate) fn take_pushes(&mut self, out: &mut Vec<ObjectPush>) {
        while let Ok(p) = self.pushes.pop() {
            match out.iter_mut().find(|o| o.id == p.id) {
                Some(o) => o.merge(&p),
                None => out.push(p),
            }
        }
    }
}

/// The rig's pieces before they are given to threads: the force stage (for the haptic thread), the
/// scene (the game thread's end, steering `collision`) and the outputs.
pub(crate) struct Parts {
    pub(crate) stage: ForceStage,
    pub(crate) scene: Scene,
    pub(crate) outputs: Outputs,
}

impl Parts {
    /// Wires a force stage to the collision pipeline steered by `collision`, with `tool` in it.
    pub(crate) fn new(
        specs: &haptico::DeviceSpecs,
        tool: ToolSpec,
        config: &RigConfig,
        mut collision: CollisionHandle,
    ) -> Result<Self> {
        let period_s = 1.0 / config.haptic.rate_hz;
        let coupling = config.coupling.unwrap_or_else(|| {
            CouplingConfig::for_device(specs.max_stiffness_n_per_m, specs.max_damping_ns_per_m, 4.0, period_s)
        });
        coupling.validate()?;
        let mut safety = config.safety.unwrap_or_else(|| safety_for(specs));
        safety.workspace = config.workspace.or(safety.workspace);
        safety.validate()?;
        let full = || RigError::QueueFull("collision");
        let tool_pose = collision.add_object(tool.tree, Pose::IDENTITY).ok_or_else(full)?;
        if let Some(shell) = tool.shell
            && !collision.set_shell(tool_pose.id(), Some(shell))
        {
            return Err(full());
        }
        if let Some(grid) = tool.surface
            && !collision.set_surface(tool_pose.id(), Some(grid))
        {
            return Err(full());
        }
        let proxy = config.rendering == Rendering::Proxy;
        // The tool against every object, in one buffer.
        let scene_input = match proxy {
            true => SceneInput::Near(collision.add_scene_near_watcher(tool_pose.id()).ok_or_else(full)?),
            false => SceneInput::Contacts(collision.add_scene_watcher(tool_pose.id()).ok_or_else(full)?),
        };
        let (telemetry_in, telemetry_out) = triple_buffer::triple_buffer(&RigTelemetry::default());
        let (forces_tx, forces_rx) = rtrb::RingBuffer::new(FORCE_COMMANDS);
        // Cannot fill: every command returns at most one object, and the scene empties this ring before
        // each command it sends (see collette's pipeline for the same argument).
        let (garbage_tx, garbage_rx) = rtrb::RingBuffer::new(FORCE_COMMANDS + MAX_OBJECTS);
        let (samples_tx, samples_rx) = rtrb::RingBuffer::new(config.force_sample_capacity.max(1));
        let (pushes_tx, pushes_rx) = rtrb::RingBuffer::new(crate::push::PUSH_RING);
        let balls = if proxy { collette::pipeline::MAX_NEAR_SPHERES } else { 0 };
        let scene = Scene::new(collision, tool_pose.id(), forces_tx, garbage_rx, config.tracks);
        let stage = ForceStage {
            map: config.map,
            rendering: config.rendering,
            coupling: VirtualCoupling::new(coupling),
            safety: SafetyLayer::new(safety),
            god: GodObject::new(),
            proxy: config.proxy,
            max_stiffness_n_per_m: specs.max_stiffness_n_per_m,
            tool: tool_pose,
            tool_center_of_mass: tool.center_of_mass,
            tool_material: tool.material,
            scene: scene_input,
            // Indexed by object slot: the tool's and one per object.
            objects: (0..=MAX_OBJECTS).map(|_| None).collect(),
            watched: 0,
            watched_since_us: 0,
            commands: forces_rx,
            garbage: garbage_tx,
            balls: Vec::with_capacity(balls),
            ball_objects: Vec::with_capacity(balls),
            grids_near: Vec::with_capacity(if proxy { collette::pipeline::MAX_TOUCHED } else { 0 }),
            telemetry: telemetry_in,
            samples: samples_tx,
            object_contacts: [crate::force::ObjectContact::default(); collette::pipeline::MAX_TOUCHED],
            touched: 0,
            push_coupling: config.pushes,
            pushes: pushes_tx,
        };
        let outputs = Outputs { samples: samples_rx, telemetry: telemetry_out, pushes: pushes_rx };
        Ok(Self { stage, scene, outputs })
    }
}

/// The running rig: both threads, steered from the game thread. Dropping it stops both.
pub struct HapticRig<D: Device + 'static> {
    haptic: Option<HapticHandle<D>>,
    scene: Mutex<Option<Scene>>,
    outputs: Mutex<Outputs>,
}

impl<D: Device + 'static> std::fmt::Debug for HapticRig<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HapticRig").finish_non_exhaustive()
    }
}

impl<D: Device + 'static> HapticRig<D> {
    /// Starts the collision thread (collette's pipeline) and the haptic thread for `device`, with `tool`
    /// attached to it. `events` may already hold your own delegates (force delegates run before the
    /// rig's force stage, so the safety layer covers them); `on_collision` delegates run on the
    /// collision thread.
    pub fn start(
        device: D,
        tool: ToolSpec,
        config: RigConfig,
        mut events: HapticEvents,
        on_collision: Delegator<OnCollision>,
    ) -> Result<Self> {
        let clock = HapticClock::new();
        let pacer = RigPacer::new(clock, &config.collision);
        let pipeline = config.collision.pipeline(None);
        let collision = CollisionThread::spawn_with(&pipeline, on_collision, pacer).map_err(RigError::Spawn)?;
        // On error, dropping the scene stops the collision thread.
        let Parts { mut stage, scene, outputs } = Parts::new(device.specs(), tool, &config, collision)?;
        events.force_on_haptic_tick.add_delegate(move |tick| stage.on_tick(tick));
        let haptic = HapticHandle::spawn(device, events, config.haptic.clone(), clock)?;
        Ok(Self { haptic: Some(haptic), scene: Mutex::new(Some(scene)), outputs: Mutex::new(outputs) })
    }

    fn scene(&self) -> std::sync::MutexGuard<'_, Option<Scene>> {
        self.scene.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn with_scene<T>(&self, f: impl FnOnce(&mut Scene) -> Result<T>) -> Result<T> {
        match self.scene().as_mut() {
            Some(scene) => f(scene),
            None => Err(RigError::QueueFull("collision")),
        }
    }

    fn outputs(&self) -> std::sync::MutexGuard<'_, Outputs> {
        self.outputs.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The haptic thread's handle (telemetry, timings, extra delegates).
    pub fn haptic(&self) -> &HapticHandle<D> {
        match &self.haptic {
            Some(h) => h,
            None => unreachable!("the haptic handle lives as long as the rig"),
        }
    }

    /// The shared clock.
    pub fn clock(&self) -> HapticClock {
        self.haptic().clock()
    }

    /// Watches objects `a` and `b` against each other (the paper's AddCollisionWatcher between two
    /// objects): the collision thread measures their overlap every step, read with
    /// [`pair_contacts`](Self::pair_contacts). Objects do not push each other. Removing either object
    /// ends the watch; replacing one keeps it.
    pub fn watch_pair(&self, a: u32, b: u32) -> Result<()> {
        self.with_scene(|s| s.watch_pair(a, b))
    }

    /// Stops watching objects `a` and `b` against each other.
    pub fn unwatch_pair(&self, a: u32, b: u32) -> Result<()> {
        self.with_scene(|s| s.unwatch_pair(a, b))
    }

    /// Appends to `out` what each watcher between two objects saw on the latest collision step.
    pub fn pair_contacts(&self, out: &mut Vec<PairContact>) {
        let _ = self.with_scene(|s| {
            s.pair_contacts(out);
            Ok(())
        });
    }

    /// Replaces the tool (its tree, centre of mass and material).
    pub fn set_tool(&self, tool: ToolSpec) -> Result<()> {
        self.with_scene(|s| s.set_tool(tool))
    }

    /// Watches an object (replaces the one with the same id).
    pub fn add_object(&self, object: ObjectSpec) -> Result<()> {
        self.with_scene(|s| s.add_object(object, None))
    }

    /// Watches an object the tool can push, a rigid body of `mass_kg` the game simulates (replaces the
    /// one with the same id): the haptic thread moves it as the tool pushes, and
    /// [`take_pushes`](Self::take_pushes) hands back the impulses to apply to the game's body, whose
    /// poses the game sends as it moves ([`set_object_pose_at`](Self::set_object_pose_at)). See
    /// [`crate::push`] for how the two stay together and passive.
    pub fn add_pushable(&self, object: ObjectSpec, mass_kg: f32) -> Result<()> {
        self.with_scene(|s| s.add_object(object, Some(mass_kg)))
    }

    /// Moves into `out` what the tool did to pushed objects since the last call: one [`ObjectPush`]
    /// per object (merged with an entry for it already in `out`), to apply to the game's bodies once
    /// a frame.
    pub fn take_pushes(&self, out: &mut Vec<ObjectPush>) {
        self.outputs().take_pushes(out);
    }

    /// Moves watched object `id` to `pose` (scene frame): the collision thread measures it there from its
    /// next step, the force stage takes its new centre of mass and orientation. The pose is the game's
    /// placement, not a sample of a moving body: it does not age (the data's age stays the tool's).
    pub fn set_object_pose(&self, id: u32, pose: Pose) -> Result<()> {
        self.with_scene(|s| s.move_object(id, pose))
    }

    /// Tells where watched object `id` was at `t_us` (on [`clock`](Self::clock), scene frame), for an
    /// object the game moves every frame: both threads read its last poses at their own time (20 ms
    /// behind by default, [`RigConfig::tracks`]), so a 60 Hz game gives a force that changes every tick,
    /// not a step per frame, and the object's velocity at the contact feeds the damping. A sample older
    /// than the newest is refused ([`RigError::BadSample`]); [`set_object_pose`](Self::set_object_pose)
    /// places it at rest again.
    pub fn set_object_pose_at(&self, id: u32, pose: Pose, t_us: u64) -> Result<()> {
        self.with_scene(|s| s.move_object_at(id, pose, t_us))
    }

    /// Stops watching object `id`.
    pub fn remove_object(&self, id: u32) -> Result<()> {
        self.with_scene(|s| s.remove_object(id))
    }

    /// Measures the tool against watched object `id`'s surface — a distance grid built from the mesh its
    /// tree came from — instead of its tree (`None`: its tree again): closer to the real overlap for a
    /// tool much smaller than the object (docs/collette.md, *Volume accuracy*).
    pub fn set_surface(&self, id: u32, surface: Option<std::sync::Arc<collette::SignedDistanceGrid>>) -> Result<()> {
        self.with_scene(|s| s.set_surface(id, surface))
    }

    /// Gives object `id` its surface shell (`collette::SurfaceShell::new(&mesh, max_edge)` of the mesh
    /// its tree was built from; `None` takes it away): with its surface grid
    /// ([`set_surface`](Self::set_surface)) and a tool that has both ([`ToolSpec::with_surface`]), the
    /// force is measured from both surfaces (`collette::overlap_surfaces`), right past the middle of the
    /// object's thin parts too.
    pub fn set_object_shell(&self, id: u32, shell: Option<std::sync::Arc<collette::SurfaceShell>>) -> Result<()> {
        self.with_scene(|s| s.set_object_shell(id, shell))
    }

    /// Only checks the objects whose bounds touch `region`, scene frame (the paper's ColletteVolume;
    /// `None`: everywhere). Objects outside it give no contact.
    pub fn set_region(&self, region: Option<collette::bounding_volume::Aabb>) -> Result<()> {
        self.with_scene(|s| s.set_region(region))
    }

    /// Pauses or resumes collision detection (paused: no new contacts, so the watchdog fades forces out).
    pub fn pause_collision(&self, paused: bool) -> Result<()> {
        self.with_scene(|s| s.pause(paused))
    }

    /// Frees what the threads handed back; returns how many items.
    pub fn collect_garbage(&self) -> usize {
        let n = self.scene().as_mut().map_or(0, Scene::collect_garbage);
        n + self.haptic().collect_garbage()
    }

    /// Latest force-stage telemetry.
    pub fn telemetry(&self) -> RigTelemetry {
        *self.outputs().telemetry.read()
    }

    /// Latest haptic-thread telemetry.
    pub fn haptic_telemetry(&self) -> HapticTelemetry {
        self.haptic().telemetry()
    }

    /// Moves recorded haptic tick timings into `out`.
    pub fn drain_haptic_timings(&self, out: &mut Vec<TickTiming>) -> usize {
        self.haptic().drain_timings(out)
    }

    /// Moves recorded collision step timings into `out`.
    pub fn drain_collision_timings(&self, out: &mut Vec<StepTiming>) -> usize {
        self.scene().as_mut().map_or(0, |s| s.collision.drain_timings(out))
    }

    /// Moves recorded per-tick force samples into `out`.
    pub fn drain_force_samples(&self, out: &mut Vec<ForceSample>) -> usize {
        let mut outputs = self.outputs();
        let mut n = 0;
        while let Ok(s) = outputs.samples.pop() {
            out.push(s);
            n += 1;
        }
        n
    }

    /// Stops both threads and returns the released device.
    pub fn stop(mut self) -> Option<D> {
        let device = self.haptic.take().and_then(|h| h.stop());
        self.scene().take(); // joins the collision thread
        device
    }
}

impl<D: Device + 'static> Drop for HapticRig<D> {
    fn drop(&mut self) {
        if let Some(h) = self.haptic.take() {
            h.stop();
        }
        self.scene().take(); // joins the collision thread
    }
}
