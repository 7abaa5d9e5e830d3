//! What the threads did since the last frame: every haptic tick's force sample and timing, every
//! collision step's timing, and the device's latest state.
//!
//! You need this module to use more than the per-frame events give: the 1 kHz force history (to drive
//! a contact sound, judge a surface, log a session), the device's buttons, whether the grip is out of
//! its workspace, or the loop's rates over windows of your own.

use bevy::prelude::*;
use haptic_common::{DeviceState, ForceTorque, Pose};
use haptic_rig::{ForceSample, StepTiming};
use haptico::TickTiming;

/// The threads' output since the last frame (refreshed in `PreUpdate`, in
/// [`HapticsSystems::Read`](crate::HapticsSystems::Read); empty until the threads run).
#[derive(Resource, Debug, Default)]
pub struct HapticFrame {
    /// The haptic clock when the frame read the threads, µs.
    pub now_us: u64,
    /// The device's latest state, device frame (pose, velocity, buttons).
    pub device: DeviceState,
    /// Where the tool is in the world (through the coupling or on the surface; the device's pose mapped
    /// to the world without `CollettePlugin`).
    pub tool: Pose,
    /// Force and torque sent to the device on the latest tick, device frame, N and N·m.
    pub output: ForceTorque,
    /// The grip is read outside the device's workspace, so forces are held off (real devices with a
    /// published workspace: Falcon, Inverse3).
    pub outside_workspace: bool,
    /// Every haptic tick's force sample since the last frame, oldest first (each field says its frame).
    pub samples: Vec<ForceSample>,
    /// Every haptic tick's timing since the last frame.
    pub ticks: Vec<TickTiming>,
    /// Every collision step's timing since the last frame (none without `CollettePlugin`).
    pub steps: Vec<StepTiming>,
}

impl HapticFrame {
    pub(crate) fn with_capacity(n: usize) -> Self {
        Self { samples: Vec::with_capacity(n), ticks: Vec::with_capacity(n), steps: Vec::with_capacity(n), ..default() }
    }

    /// Whether any button of `mask` is held (bit i: button i).
    pub fn pressed(&self, mask: u32) -> bool {
        self.device.buttons.0 & mask != 0
    }
}
