//! A mock device for tests: a fixed pose, and counters the test can read from another thread.
//!
//! You need this module to test code that drives a [`Device`] without simulating one.

use std::sync::Arc;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use glam::Vec3;
use haptic_common::{DeviceState, ForceTorque, Pose};

use crate::{Device, DeviceSpecs, presets};

/// What a [`MockDevice`] saw, shared with the test (atomics only: readable while the thread runs).
#[derive(Debug, Default)]
pub struct MockLog {
    reads: AtomicU64,
    commands: AtomicU64,
    last_force: [AtomicU32; 3],
    released: AtomicU64,
}

impl MockLog {
    /// Number of `read_state` calls.
    pub fn reads(&self) -> u64 {
        self.reads.load(Ordering::Acquire)
    }
    /// Number of `command` calls.
    pub fn commands(&self) -> u64 {
        self.commands.load(Ordering::Acquire)
    }
    /// The last commanded force, N.
    pub fn last_force(&self) -> Vec3 {
        let c = |i: usize| f32::from_bits(self.last_force[i].load(Ordering::Acquire));
        Vec3::new(c(0), c(1), c(2))
    }
    /// Number of `release` calls.
    pub fn releases(&self) -> u64 {
        self.released.load(Ordering::Acquire)
    }
}

/// A device that stays at one pose and records what it is told.
#[derive(Debug)]
pub struct MockDevice {
    specs: DeviceSpecs,
    pose: Pose,
    log: Arc<MockLog>,
}

impl MockDevice {
    /// A mock with the given specs at the identity pose, and the log to watch it with.
    pub fn new(specs: DeviceSpecs) -> (Self, Arc<MockLog>) {
        let log = Arc::new(MockLog::default());
        (Self { specs, pose: Pose::IDENTITY, log: log.clone() }, log)
    }

    /// A mock Touch.
    pub fn touch() -> (Self, Arc<MockLog>) {
        Self::new(presets::touch())
    }
}

impl Device for MockDevice {
    fn specs(&self) -> &DeviceSpecs {
        &self.specs
    }

    fn read_state(&mut self, t_us: u64) -> DeviceState {
        self.log.reads.fetch_add(1, Ordering::AcqRel);
        DeviceState { pose: self.pose, timestamp_us: t_us, ..DeviceState::default() }
    }

    fn command(&mut self, ft: ForceTorque) {
        for i in 0..3 {
            self.log.last_force[i].store(ft.force[i].to_bits(), Ordering::Release);
        }
        self.log.commands.fetch_add(1, Ordering::AcqRel);
    }

    fn release(&mut self) {
        self.command(ForceTorque::ZERO);
        self.log.released.fetch_add(1, Ordering::AcqRel);
    }
}
