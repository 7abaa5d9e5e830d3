//! Where the touch bot feels a copy: the client's running haptics in real time ([`RealTimeHaptics`]: a
//! headless Bevy app with `bevy_haptics`, set up as the client sets it up), or the same loop stepped in
//! simulated time on the caller's thread ([`LockstepHaptics`]).
//!
//! You need this module to explore a copy outside a session ([`crate::explore::feel`]): the tests and
//! the `feel_copies` example. The lockstep bench renders the same forces from the same rig (force stage,
//! collision world, safety layer, steered simulated hand) with a collision step before every haptic
//! tick and exact queries, so an exploration takes the machine's time its computing takes, not the haptic
//! clock's, and comes out the same on every run; it says nothing about the loop's real-time rates, which
//! only [`RealTimeHaptics`] shows.

use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy_haptics::{HapticFrame, HapticStatus, SimulatedHand};
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ForceSample, ObjectSpec, Rendering, WorkspaceMap};
use heist_shared::protocol::WorkbenchCopy;

use crate::bench::{Bench, CopyLanded, LoopRates, add_haptics, stylus};
use crate::device::{self, DeviceChoice, HandControl, HandGoal, SteeredSim};
use crate::error::ClientError;
use crate::haptics::{
    BuiltCopy, COPY_OBJECT, HapticsSettings, RateWindow, RigSetup, build_copy, haptic_material, proxy_hard_above,
};

/// What the touch bot needs of a haptic loop.
pub trait TouchBench {
    /// Places `copy` on the bench (replacing what was there) and returns once it can be felt.
    fn place_and_wait(&mut self, copy: &WorkbenchCopy) -> Result<(), String>;
    /// The haptic clock, µs.
    fn now_us(&self) -> u64;
    /// Where the stylus's tip is, in the scene (the workbench's) frame.
    fn stylus(&mut self) -> Vec3;
    /// With proxy rendering, the resting force over depth (N/m) above which a copy feels hard.
    fn hard_above_n_per_m(&self) -> Option<f32>;
    /// Device frame to scene.
    fn map(&self) -> WorkspaceMap;
    /// Sends the simulated hand after `goal` (in the device frame).
    fn steer(&mut self, goal: HandGoal) -> Result<(), String>;
    /// Lets about `ms` milliseconds of haptic time pass.
    fn wait(&mut self, ms: u64);
    /// The force samples of the ticks during the last [`wait`](Self::wait).
    fn samples(&self) -> &[ForceSample];
}

/// The client's haptics in real time, outside a session: a headless Bevy app with nothing but
/// [`add_haptics`] (the haptic and collision threads at 1 kHz, the copy built on the async compute pool),
/// updated by the caller.
pub struct RealTimeHaptics {
    app: App,
}

impl RealTimeHaptics {
    /// Opens the device and starts the threads, then waits the 2.5 s in which the safety layer ramps
    /// forces in.
    pub fn start(settings: HapticsSettings) -> Result<Self, ClientError> {
        let mut app = App::new();
        app.add_plugins(MinimalPlugins);
        add_haptics(&mut app, &settings)?;
        app.update();
        if let HapticStatus::Failed(reason) = app.world().resource::<HapticStatus>() {
            return Err(ClientError::Device(reason.clone()));
        }
        let mut haptics = Self { app };
        haptics.wait(2_500);
        Ok(haptics)
    }

    /// The copy on the bench and how forces are rendered.
    pub fn bench(&self) -> &Bench {
        self.app.world().resource::<Bench>()
    }

    /// Every complete one-second window of both loops so far.
    pub fn rates(&self) -> &[RateWindow] {
        &self.app.world().resource::<LoopRates>().rates
    }

    fn frame(&self) -> &HapticFrame {
        self.app.world().resource::<HapticFrame>()
    }

    /// Stops both threads (as an exiting app does).
    pub fn stop(mut self) {
        self.app.world_mut().write_message(AppExit::Success);
        self.app.update();
    }
}

impl TouchBench for RealTimeHaptics {
    fn place_and_wait(&mut self, copy: &WorkbenchCopy) -> Result<(), String> {
        self.app.world_mut().resource_mut::<Bench>().place(copy);
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            self.app.update();
            let landed = self.app.world_mut().resource_mut::<Messages<CopyLanded>>().drain().last();
            if let Some(CopyLanded { result, .. }) = landed {
                // The collider reaches the collision thread in this update's `PostUpdate`.
                self.app.update();
                return result.map(drop);
            }
            if Instant::now() > deadline {
                return Err("the tree was not built within a minute".into());
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    fn now_us(&self) -> u64 {
        self.app.world().get_resource::<SimulatedHand>().map_or(self.frame().now_us, SimulatedHand::now_us)
    }

    fn stylus(&mut self) -> Vec3 {
        stylus(&self.bench().map, self.frame())
    }

    fn hard_above_n_per_m(&self) -> Option<f32> {
        self.bench().hard_above_n_per_m()
    }

    fn map(&self) -> WorkspaceMap {
        self.bench().map
    }

    fn steer(&mut self, goal: HandGoal) -> Result<(), String> {
        let mut hand =
            self.app.world_mut().get_resource_mut::<SimulatedHand>().ok_or("the device has no steerable hand")?;
        hand.set(goal);
        Ok(())
    }

    fn wait(&mut self, ms: u64) {
        std::thread::sleep(Duration::from_millis(ms));
        self.app.update();
    }

    fn samples(&self) -> &[ForceSample] {
        &self.frame().samples
    }
}

/// The client's haptic rig with the simulated device, stepped tick by tick on the caller's thread.
pub struct LockstepHaptics {
    rig: Lockstep<SteeredSim>,
    hand: HandControl,
    /// The haptic clock, µs.
    t_us: u64,
    rendering: Rendering,
    stiffness_scale: f32,
    map: WorkspaceMap,
    tool_reference_volume_m3: f32,
    settings: HapticsSettings,
    on_bench: bool,
    samples: Vec<ForceSample>,
}

/// One haptic tick at 1 kHz, µs.
const TICK_US: u64 = 1_000;

impl LockstepHaptics {
    /// The rig the client starts for these settings, with the simulated hand (the only device a
    /// lockstep rig can step), after the 2.5 s in which the safety layer ramps forces in.
    pub fn start(settings: HapticsSettings) -> Result<Self, ClientError> {
        if !matches!(settings.device, DeviceChoice::Sim) {
            return Err(ClientError::Device("a lockstep rig steps the simulated device only".into()));
        }
        let specs = device::preset(settings.preset.as_deref())?;
        let (sim, hand) = SteeredSim::new(specs.clone(), Pose::new(device::START, Quat::IDENTITY));
        let RigSetup { tool, config, rendering, stiffness_scale, map, tool_reference_volume_m3 } =
            RigSetup::new(&specs, &settings)?;
        let rig = Lockstep::new(sim, tool, &config, 1, None)?;
        let mut bench = Self {
            rig,
            hand,
            t_us: 0,
            rendering,
            stiffness_scale,
            map,
            tool_reference_volume_m3,
            settings,
            on_bench: false,
            samples: Vec::with_capacity(1 << 14),
        };
        bench.wait(2_500);
        Ok(bench)
    }

    /// How forces are rendered (the choice resolved for the device).
    pub fn rendering(&self) -> Rendering {
        self.rendering
    }
}

impl TouchBench for LockstepHaptics {
    fn place_and_wait(&mut self, copy: &WorkbenchCopy) -> Result<(), String> {
        if std::mem::take(&mut self.on_bench) {
            self.rig.remove_object(COPY_OBJECT).map_err(|e| e.to_string())?;
            self.rig.collect_garbage();
        }
        let with_surface = self.rendering != Rendering::Proxy;
        let BuiltCopy { tree, surface, .. } =
            build_copy(&copy.mesh, self.settings.spheres, self.settings.cache_dir.as_deref(), with_surface)?;
        let material = haptic_material(&copy.material, self.tool_reference_volume_m3).material();
        let object = ObjectSpec { id: COPY_OBJECT, tree: Arc::new(tree), pose: Pose::IDENTITY, material };
        self.rig.add_object(object).map_err(|e| e.to_string())?;
        if let Some(grid) = surface {
            self.rig.set_surface(COPY_OBJECT, Some(Arc::new(grid))).map_err(|e| e.to_string())?;
        }
        self.on_bench = true;
        Ok(())
    }

    fn now_us(&self) -> u64 {
        self.t_us
    }

    fn stylus(&mut self) -> Vec3 {
        self.map.to_scene(&self.rig.telemetry().device.pose).translation
    }

    fn hard_above_n_per_m(&self) -> Option<f32> {
        proxy_hard_above(self.rendering, self.stiffness_scale)
    }

    fn map(&self) -> WorkspaceMap {
        self.map
    }

    fn steer(&mut self, goal: HandGoal) -> Result<(), String> {
        self.hand.set(goal);
        Ok(())
    }

    fn wait(&mut self, ms: u64) {
        for _ in 0..ms {
            self.t_us += TICK_US;
            self.rig.tick(self.t_us);
        }
        self.samples.clear();
        self.rig.drain_force_samples(&mut self.samples);
    }

    fn samples(&self) -> &[ForceSample] {
        &self.samples
    }
}
