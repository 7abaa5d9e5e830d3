//! Both stages of the rig in one thread, on simulated time: the same force stage and collision world as
//! [`HapticRig`](crate::HapticRig), stepped in a fixed order with no clock and no scheduler.
//!
//! You need this module for deterministic tests and offline analysis (e.g. checking the safety limits
//! along the whole benchmark trajectory); it says nothing about real-time rates.

use std::time::Duration;

use collette::pipeline::CollisionStepper;
use haptic_common::{Delegator, ForceTorque};
use haptico::{Device, HapticCore, HapticEvents};

use crate::force::{ForceSample, RigTelemetry};
use crate::rig::{Outputs, Parts};
use crate::scene::Scene;
use crate::spec::{ObjectSpec, ToolSpec};
use crate::{Result, RigConfig};

/// A rig without threads.
pub struct Lockstep<D: Device> {
    core: HapticCore<D>,
    stepper: CollisionStepper,
    scene: Scene,
    outputs: Outputs,
    collision_every: u64,
    budgeted: bool,
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
        let (collision, stepper) = collette::pipeline::pipeline(&config.collision.pipeline(budget), Delegator::new());
        let Parts { mut stage, scene, outputs } = Parts::new(device.specs(), tool, config, collision)?;
        let mut events = HapticEvents::default();
        events.force_on_haptic_tick.add_delegate(move |tick| stage.on_tick(tick));
        let core = HapticCore::new(device, events, config.haptic.rate_hz);
        Ok(Self {
            core,
            stepper,
            scene,
            outputs,
            collision_every: collision_every.max(1),
            budgeted: budget.is_some(),
            paused: false,
        })
    }

    /// Watches an object.
    pub fn add_object(&mut self, object: ObjectSpec) -> Result<()> {
        self.scene.add_object(object, None)
    }

    /// Watches an object the tool can push (see [`HapticRig::add_pushable`](crate::HapticRig::add_pushable)).
    pub fn add_pushable(&mut self, object: ObjectSpec, mass_kg: f32) -> Result<()> {
        self.scene.add_object(object, Some(mass_kg))
    }

    /// Moves what the tool did to pushed objects into `out` (see
    /// [`HapticRig::take_pushes`](crate::HapticRig::take_pushes)).
    pub fn take_pushes(&mut self, out: &mut Vec<crate::ObjectPush>) {
        self.outputs.take_pushes(out);
    }

    /// Moves watched object `id` to `pose` (see [`HapticRig::set_object_pose`](crate::HapticRig::set_object_pose)).
    pub fn set_object_pose(&mut self, id: u32, pose: haptic_common::Pose) -> Result<()> {
        self.scene.move_object(id, pose)
    }

    /// Tells where watched object `id` was at `t_us` (see
    /// [`HapticRig::set_object_pose_at`](crate::HapticRig::set_object_pose_at)).
    pub fn set_object_pose_at(&mut self, id: u32, pose: haptic_common::Pose, t_us: u64) -> Result<()> {
        self.scene.move_object_at(id, pose, t_us)
    }

    /// Stops watching object `id`.
    pub fn remove_object(&mut self, id: u32) -> Result<()> {
        self.scene.remove_object(id)
    }

    /// Measures the tool against watched object `id`'s surface grid (`None`: its tree again).
    pub fn set_surface(
        &mut self,
        id: u32,
        surface: Option<std::sync::Arc<collette::SignedDistanceGrid>>,
    ) -> Result<()> {
        self.scene.set_surface(id, surface)
    }

    /// See [`HapticRig::set_object_shell`](crate::HapticRig::set_object_shell).
    pub fn set_object_shell(&mut self, id: u32, shell: Option<std::sync::Arc<collette::SurfaceShell>>) -> Result<()> {
        self.scene.set_object_shell(id, shell)
    }

    /// Replaces the tool.
    pub fn set_tool(&mut self, tool: ToolSpec) -> Result<()> {
        self.scene.set_tool(tool)
    }

    /// Frees what the stages handed back; returns how many objects the force stage returned.
    pub fn collect_garbage(&mut self) -> usize {
        self.scene.collect_garbage()
    }

    /// Removed or replaced objects, trees and watchers the collision stage could not hand back (leaked
    /// rather than freed on its thread): always 0, its return ring cannot fill.
    pub fn collision_leaks(&self) -> u64 {
        self.scene.collision.leaked()
    }

    /// Stops or restarts collision steps (stale data: the watchdog fades forces out).
    pub fn pause_collision(&mut self, paused: bool) {
        self.paused = paused;
    }

    /// One haptic tick at `t_us` (preceded by a collision step when due); returns the device command.
    pub fn tick(&mut self, t_us: u64) -> ForceTorque {
        if !self.paused && self.core.ticks().is_multiple_of(self.collision_every) {
            self.stepper.step(t_us, self.budgeted, || t_us);
        }
        self.core.tick(t_us)
    }

    /// The device.
    pub fn device(&self) -> &D {
        self.core.device()
    }

    /// Latest force-stage telemetry.
    pub fn telemetry(&mut self) -> RigTelemetry {
        *self.outputs.telemetry.read()
    }

    /// Moves recorded per-tick force samples into `out`.
    pub fn drain_force_samples(&mut self, out: &mut Vec<ForceSample>) -> usize {
        let mut n = 0;
        while let Ok(s) = self.outputs.samples.pop() {
            out.push(s);
            n += 1;
        }
        n
    }
}
