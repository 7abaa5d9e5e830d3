//! The assembled loop and the control handle the game thread uses (the paper's EventHandler).
//!
//! You need this module to run the full stack: device → OnTransform / ForceOnHapticTick (haptic thread)
//! → tool pose → collision thread (collette) → contacts → force stage (forcecomp) → device.

use std::sync::Mutex;
use std::thread::JoinHandle;

use forcecomp::{CouplingConfig, GodObject, SafetyConfig, SafetyLayer, VirtualCoupling};
use haptic_common::{Delegator, OnCollision};
use haptico::{Device, HapticClock, HapticConfig, HapticEvents, HapticHandle, HapticTelemetry, TickTiming};

use crate::collision::{CollisionConfig, CollisionWorld, StepTiming, WatchedObject, WorldCommand, WorldGarbage};
use crate::force::{ForceSample, ForceStage, ProxyRendering, Rendering, RigTelemetry};
use crate::frame::{CollisionFrame, MAX_OBJECTS, ObjectSpec, ToolPoseMsg, ToolSpec};
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
    /// Safety limits (None: the device's peak force and torque with the default habits).
    pub safety: Option<SafetyConfig>,
    /// Coupled, direct or 3-DOF proxy rendering (default coupled).
    pub rendering: Rendering,
    /// How the 3-DOF proxy feels materials (with `Rendering::Proxy`).
    pub proxy: ProxyRendering,
    /// Capacity of the per-tick force-sample ring (default 65 536).
    pub force_sample_capacity: usize,
}

impl Default for RigConfig {
    fn default() -> Self {
        Self {
            haptic: HapticConfig::default(),
            collision: CollisionConfig::default(),
            map: WorkspaceMap::default(),
            coupling: None,
            safety: None,
            rendering: Rendering::Coupled,
            proxy: ProxyRendering::default(),
            force_sample_capacity: 1 << 16,
        }
    }
}

pub(crate) struct RigInner {
    pub(crate) commands: rtrb::Producer<WorldCommand>,
    pub(crate) garbage: rtrb::Consumer<WorldGarbage>,
    pub(crate) timings: rtrb::Consumer<StepTiming>,
    pub(crate) samples: rtrb::Consumer<ForceSample>,
    pub(crate) telemetry: triple_buffer::Output<RigTelemetry>,
    pub(crate) collision: Option<JoinHandle<CollisionWorld>>,
    pub(crate) objects: usize,
}

/// The three pieces of a rig before they are given to threads.
pub(crate) struct Parts {
    pub(crate) stage: ForceStage,
    pub(crate) world: CollisionWorld,
    pub(crate) inner: RigInner,
}

impl Parts {
    pub(crate) fn new(
        specs: &haptico::DeviceSpecs,
        tool: ToolSpec,
        config: &RigConfig,
        on_collision: Delegator<OnCollision>,
    ) -> Result<Self> {
        let period_s = 1.0 / config.haptic.rate_hz;
        let coupling = config.coupling.unwrap_or_else(|| {
            CouplingConfig::for_device(specs.max_stiffness_n_per_m, specs.max_damping_ns_per_m, 4.0, period_s)
        });
        coupling.validate()?;
        let safety = config.safety.unwrap_or_else(|| SafetyConfig::for_limits(specs.peak_force_n, specs.max_torque_nm));
        safety.validate()?;
        let (pose_in, pose_out) = triple_buffer::triple_buffer(&ToolPoseMsg::default());
        let (frame_in, frame_out) = triple_buffer::triple_buffer(&CollisionFrame::default());
        let (telemetry_in, telemetry_out) = triple_buffer::triple_buffer(&RigTelemetry::default());
        let (commands_tx, commands_rx) = rtrb::RingBuffer::new(64);
        let (garbage_tx, garbage_rx) = rtrb::RingBuffer::new(128);
        let (timings_tx, timings_rx) = rtrb::RingBuffer::new(config.collision.timing_capacity.max(1));
        let (samples_tx, samples_rx) = rtrb::RingBuffer::new(config.force_sample_capacity.max(1));
        let world = CollisionWorld {
            tool: Box::new(tool),
            objects: Vec::with_capacity(MAX_OBJECTS),
            workspace: collette::query::QueryWorkspace::new(),
            poses: pose_out,
            frames: frame_in,
            commands: commands_rx,
            garbage: garbage_tx,
            timings: timings_tx,
            on_collision,
            proxy: config.rendering == Rendering::Proxy,
            paused: false,
            sequence: 0,
            last_start_us: None,
        };
        let stage = ForceStage {
            map: config.map,
            rendering: config.rendering,
            coupling: VirtualCoupling::new(coupling),
            safety: SafetyLayer::new(safety),
            god: GodObject::new(),
            proxy: config.proxy,
            max_stiffness_n_per_m: specs.max_stiffness_n_per_m,
            source: crate::force::Source::Rig { frames: frame_out, poses: pose_in },
            telemetry: telemetry_in,
            samples: samples_tx,
        };
        let inner = RigInner {
            commands: commands_tx,
            garbage: garbage_rx,
            timings: timings_rx,
            samples: samples_rx,
            telemetry: telemetry_out,
            collision: None,
            objects: 0,
        };
        Ok(Self { stage, world, inner })
    }
}

/// The running rig: both threads, steered from the game thread. Dropping it stops both.
pub struct HapticRig<D: Device + 'static> {
    haptic: Option<HapticHandle<D>>,
    inner: Mutex<RigInner>,
    collette: Option<Mutex<collette::pipeline::CollisionHandle>>,
    _static_poses: Mutex<Vec<collette::pipeline::PoseWriter>>,
}

impl<D: Device + 'static> std::fmt::Debug for HapticRig<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HapticRig").finish_non_exhaustive()
    }
}

impl<D: Device + 'static> HapticRig<D> {
    /// Starts the collision thread and the haptic thread for `device`, with `tool` attached to it.
    /// `events` may already hold your own delegates (force delegates run before the rig's force stage, so
    /// the safety layer covers them); `on_collision` delegates run on the collision thread.
    pub fn start(
        device: D,
        tool: ToolSpec,
        config: RigConfig,
        mut events: HapticEvents,
        on_collision: Delegator<OnCollision>,
    ) -> Result<Self> {
        let clock = HapticClock::new();
        let Parts { mut stage, world, inner } = Parts::new(device.specs(), tool, &config, on_collision)?;
        let collision_config = config.collision.clone();
        let collision = std::thread::Builder::new()
            .name("collision".into())
            .spawn(move || world.run(clock, collision_config))
            .map_err(RigError::Spawn)?;
        events.force_on_haptic_tick.add_delegate(move |tick| stage.on_tick(tick));
        let haptic = HapticHandle::spawn(device, events, config.haptic.clone(), clock);
        let mut rig = Self {
            haptic: None,
            inner: Mutex::new(RigInner { collision: Some(collision), ..inner }),
            collette: None,
            _static_poses: Mutex::new(Vec::new()),
        };
        // On error, dropping `rig` stops the collision thread.
        rig.haptic = Some(haptic?);
        Ok(rig)
    }

    /// Like [`HapticRig::start`], but collision detection runs in collette's own pipeline thread
    /// (`collette::pipeline`), watching the tool against each of `objects` (fixed for the rig's life:
    /// `add_object`/`remove_object`/`pause_collision` then answer `Unsupported`). No collision step
    /// timings are recorded in this mode; the force samples' sequence numbers show its rate.
    pub fn start_with_collette(
        device: D,
        tool: ToolSpec,
        objects: Vec<ObjectSpec>,
        config: RigConfig,
        mut events: HapticEvents,
    ) -> Result<Self> {
        if config.rendering == Rendering::Proxy {
            return Err(RigError::Unsupported(
                "with proxy rendering on collette's pipeline (it gives overlaps, not spheres)",
            ));
        }
        let clock = HapticClock::new();
        let Parts { mut stage, world, inner } = Parts::new(device.specs(), tool.clone(), &config, Delegator::new())?;
        drop(world);
        let mut pipeline = collette::pipeline::CollisionThread::spawn(collette::pipeline::CollisionConfig {
            period: std::time::Duration::from_secs_f64(1.0 / config.collision.rate_hz.max(1.0) as f64),
            step_budget: std::time::Duration::from_micros(config.collision.budget_us as u64),
            ..Default::default()
        })
        .map_err(RigError::Spawn)?;
        let full = || RigError::QueueFull("collette");
        let tool_writer = pipeline.add_object(tool.tree.clone(), haptic_common::Pose::IDENTITY).ok_or_else(full)?;
        let mut readers = Vec::with_capacity(objects.len());
        let mut writers = Vec::with_capacity(objects.len());
        for object in objects {
            let watched = WatchedObject::boxed(object);
            let writer = pipeline.add_object(watched.spec.tree.clone(), watched.spec.pose).ok_or_else(full)?;
            let reader = pipeline.add_watcher(tool_writer.id(), writer.id()).ok_or_else(full)?;
            readers.push((reader, watched.spec.material, watched.motion));
            writers.push(writer);
        }
        stage.source = crate::force::Source::Collette(Box::new(crate::force::ColletteSource {
            tool: tool_writer,
            tool_center_of_mass: tool.center_of_mass,
            tool_material: tool.material,
            objects: readers,
            last_sequence: 0,
            last_change_us: 0,
        }));
        events.force_on_haptic_tick.add_delegate(move |tick| stage.on_tick(tick));
        let haptic = HapticHandle::spawn(device, events, config.haptic.clone(), clock)?;
        Ok(Self {
            haptic: Some(haptic),
            inner: Mutex::new(inner),
            collette: Some(Mutex::new(pipeline)),
            _static_poses: Mutex::new(writers),
        })
    }

    fn refuse_in_collette_mode(&self) -> Result<()> {
        if self.collette.is_some() { Err(RigError::Unsupported("with collette's pipeline thread")) } else { Ok(()) }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, RigInner> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn send(&self, command: WorldCommand) -> Result<()> {
        self.lock().commands.push(command).map_err(|_| RigError::QueueFull("collision"))
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

    /// Replaces the tool (its tree, centre of mass and material).
    pub fn set_tool(&self, tool: ToolSpec) -> Result<()> {
        self.refuse_in_collette_mode()?;
        self.send(WorldCommand::SetTool(Box::new(tool)))
    }

    /// Watches an object (replaces the one with the same id).
    pub fn add_object(&self, object: ObjectSpec) -> Result<()> {
        self.refuse_in_collette_mode()?;
        let boxed = WatchedObject::boxed(object);
        let mut inner = self.lock();
        if inner.objects >= MAX_OBJECTS {
            return Err(RigError::TooManyObjects(MAX_OBJECTS));
        }
        inner.commands.push(WorldCommand::AddObject(boxed)).map_err(|_| RigError::QueueFull("collision"))?;
        inner.objects += 1;
        Ok(())
    }

    /// Stops watching object `id`.
    pub fn remove_object(&self, id: u32) -> Result<()> {
        self.refuse_in_collette_mode()?;
        let mut inner = self.lock();
        inner.commands.push(WorldCommand::RemoveObject(id)).map_err(|_| RigError::QueueFull("collision"))?;
        inner.objects = inner.objects.saturating_sub(1);
        Ok(())
    }

    /// Pauses or resumes collision detection (paused: no new frames, so the watchdog fades forces out).
    pub fn pause_collision(&self, paused: bool) -> Result<()> {
        self.refuse_in_collette_mode()?;
        self.send(WorldCommand::Pause(paused))
    }

    /// Frees what the collision thread handed back; returns how many items.
    pub fn collect_garbage(&self) -> usize {
        let mut inner = self.lock();
        let mut n = 0;
        while inner.garbage.pop().is_ok() {
            n += 1;
        }
        if let Some(c) = &self.collette {
            c.lock().unwrap_or_else(|p| p.into_inner()).collect_retired();
        }
        n + self.haptic().collect_garbage()
    }

    /// Latest force-stage telemetry.
    pub fn telemetry(&self) -> RigTelemetry {
        *self.lock().telemetry.read()
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
        let mut inner = self.lock();
        let mut n = 0;
        while let Ok(t) = inner.timings.pop() {
            out.push(t);
            n += 1;
        }
        n
    }

    /// Moves recorded per-tick force samples into `out`.
    pub fn drain_force_samples(&self, out: &mut Vec<ForceSample>) -> usize {
        let mut inner = self.lock();
        let mut n = 0;
        while let Ok(s) = inner.samples.pop() {
            out.push(s);
            n += 1;
        }
        n
    }

    /// Stops both threads and returns the released device.
    pub fn stop(mut self) -> Option<D> {
        let device = self.haptic.take().and_then(|h| h.stop());
        self.stop_collision();
        device
    }

    fn stop_collision(&self) {
        let mut inner = self.lock();
        let Some(join) = inner.collision.take() else { return };
        while inner.commands.push(WorldCommand::Stop).is_err() && !join.is_finished() {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        drop(inner);
        let _ = join.join();
        let mut inner = self.lock();
        while inner.garbage.pop().is_ok() {}
    }
}

impl<D: Device + 'static> Drop for HapticRig<D> {
    fn drop(&mut self) {
        if let Some(h) = self.haptic.take() {
            h.stop();
        }
        self.stop_collision();
    }
}
