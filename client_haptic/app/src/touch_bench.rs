//! Where the touch bot feels a copy: the client's running haptic loop in real time ([`Haptics`]), or the
//! same loop stepped in simulated time on the caller's thread ([`LockstepHaptics`]).
//!
//! You need this module to explore a copy outside a session ([`crate::explore::feel`]): the tests and
//! the `feel_copies` example. The lockstep bench renders the same forces from the same rig (force stage,
//! collision world, safety layer, steered simulated hand) with a collision step before every haptic
//! tick and exact queries, so an exploration takes the machine's time its computing takes, not the haptic
//! clock's, and comes out the same on every run; it says nothing about the loop's real-time rates, which
//! only [`Haptics`] shows.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{Quat, Vec3};
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ForceSample, ObjectSpec, Rendering, WorkspaceMap};
use heist_shared::protocol::WorkbenchCopy;

use crate::device::{self, DeviceChoice, HandControl, HandGoal, SteeredSim};
use crate::error::ClientError;
use crate::haptics::{
    BuiltCopy, COPY_OBJECT, Haptics, HapticsSettings, RigSetup, build_copy, haptic_material, proxy_hard_above,
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

impl TouchBench for Haptics {
    fn place_and_wait(&mut self, copy: &WorkbenchCopy) -> Result<(), String> {
        self.place(copy);
        let deadline = Instant::now() + Duration::from_secs(60);
        while self.on_bench.is_none() {
            if Instant::now() > deadline {
                return Err("the tree was not built within a minute".into());
            }
            if let Some(Err(e)) = self.poll() {
                return Err(e.to_string());
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        Ok(())
    }

    fn now_us(&self) -> u64 {
        Haptics::now_us(self)
    }

    fn stylus(&mut self) -> Vec3 {
        Haptics::stylus(self)
    }

    fn hard_above_n_per_m(&self) -> Option<f32> {
        Haptics::hard_above_n_per_m(self)
    }

    fn map(&self) -> WorkspaceMap {
        self.map
    }

    fn steer(&mut self, goal: HandGoal) -> Result<(), String> {
        self.hand.as_mut().map(|c| c.set(goal)).ok_or_else(|| "the device has no steerable hand".into())
    }

    fn wait(&mut self, ms: u64) {
        std::thread::sleep(Duration::from_millis(ms));
        self.poll();
    }

    fn samples(&self) -> &[ForceSample] {
        &self.samples
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
    /// The rig [`Haptics::start`] starts for these settings, with the simulated hand (the only device a
    /// lockstep rig can step), after the 2.5 s in which the safety layer ramps forces in.
    pub fn start(settings: HapticsSettings) -> Result<Self, ClientError> {
        if !matches!(settings.device, DeviceChoice::Sim) {
            return Err(ClientError::Device("a lockstep rig steps the simulated device only".into()));
        }
        let specs = device::preset(settings.preset.as_deref())?;
        let (sim, hand) = SteeredSim::new(specs.clone(), Pose::new(device::START, Quat::IDENTITY));
        let RigSetup { tool, config, rendering, stiffness_scale, map, tool_reference_volume_m3 } =
            RigSetup::new(&specs, &settings, None)?;
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
        let material = haptic_material(&copy.material, self.tool_reference_volume_m3);
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
