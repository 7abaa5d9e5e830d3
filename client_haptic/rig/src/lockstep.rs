//! Both stages of the rig in one thread, on simulated time: the same force stage and collision world as
//! [`HapticRig`](crate::HapticRig), stepped in a fixed order with no clock and no scheduler.
//!
//! You need this module for deterministic tests and offline analysis (e.g. checking the safety limits
//! along the whole benchmark trajectory); it says nothing about real-time rates.

use std::time::{Duration, Instant};

use haptic_common::{Delegator, ForceTorque};
use haptico::{Device, HapticClock, HapticCore, HapticEvents};

use crate::collision::{CollisionWorld, WatchedObject, WorldCommand};
use crate::force::{ForceSample, RigTelemetry};
use crate::frame::{ObjectSpec, ToolSpec};
use crate::rig::{Parts, RigInner};
use crate::{Result, RigConfig, RigError};

/// A rig without threads.
pub struct Lockstep<D: Device> {
    core: HapticCore<D>,
    world: CollisionWorld,
    inner: RigInner,
    clock: HapticClock,
    collision_every: u64,
    budget: Option<Duration>,
    paused: bool,
}

impl<D: Device> Lockstep<D> {
    /// A lockstep rig; the collision step runs before every `collision_every`-th haptic tick, using the
    /// tool pose of the tick before (as the threaded rig does at best). `budget` limits each step's
    /// queries in wall-clock time (None: exact queries, fully deterministic).
    pub fn new(
        device: D,
        tool: ToolSpec,
        config: &RigConfig,
        collision_every: u64,
        budget: Option<Duration>,
    ) -> Result<Self> {
        let Parts { mut stage, world, inner } = Parts::new(device.specs(), tool, config, Delegator::new())?;
        let mut events = HapticEvents::default();
        events.force_on_haptic_tick.add_delegate(move |tick| stage.on_tick(tick));
        let core = HapticCore::new(device, events, config.haptic.rate_hz);
        Ok(Self {
            core,
            world,
            inner,
            clock: HapticClock::new(),
            collision_every: collision_every.max(1),
            budget,
            paused: false,
        })
    }

    /// Watches an object.
    pub fn add_object(&mut self, object: ObjectSpec) -> Result<()> {
        self.inner
            .commands
            .push(WorldCommand::AddObject(WatchedObject::boxed(object)))
            .map_err(|_| RigError::QueueFull("collision"))
    }

    /// Stops or restarts collision steps (stale data: the watchdog fades forces out).
    pub fn pause_collision(&mut self, paused: bool) {
        self.paused = paused;
    }

    /// One haptic tick at `t_us` (preceded by a collision step when due); returns the device command.
    pub fn tick(&mut self, t_us: u64) -> ForceTorque {
        if !self.paused && self.core.ticks().is_multiple_of(self.collision_every) {
            self.world.apply_commands();
            self.world.step(&self.clock, t_us, self.budget.map(|b| Instant::now() + b));
        }
        self.core.tick(t_us)
    }

    /// The device.
    pub fn device(&self) -> &D {
        self.core.device()
    }

    /// Latest force-stage telemetry.
    pub fn telemetry(&mut self) -> RigTelemetry {
        *self.inner.telemetry.read()
    }

    /// Moves recorded per-tick force samples into `out`.
    pub fn drain_force_samples(&mut self, out: &mut Vec<ForceSample>) -> usize {
        let mut n = 0;
        while let Ok(s) = self.inner.samples.pop() {
            out.push(s);
            n += 1;
        }
        n
    }
}
