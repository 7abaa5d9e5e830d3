//! Device state (the OnTransform event's payload) and force commands (ForceOnHapticTick's result).

use glam::Vec3;

use crate::Pose;

/// Pressed buttons as a bit set (bit i = button i).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Buttons(pub u32);

impl Buttons {
    /// True when button `index` is held.
    pub fn pressed(self, index: u32) -> bool {
        index < 32 && self.0 & (1 << index) != 0
    }
}

/// One sample of a haptic device's end effector, in the device's workspace frame (metres, m/s, rad/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DeviceState {
    /// Pose of the end effector.
    pub pose: Pose,
    /// Linear velocity, m/s.
    pub linear_velocity: Vec3,
    /// Angular velocity, rad/s.
    pub angular_velocity: Vec3,
    /// Buttons held.
    pub buttons: Buttons,
    /// Sample time on the haptic clock, microseconds.
    pub timestamp_us: u64,
}

/// A force (N) and a torque (N·m) to command on a device.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ForceTorque {
    /// Force, newtons.
    pub force: Vec3,
    /// Torque, newton-metres.
    pub torque: Vec3,
}

impl ForceTorque {
    /// No force, no torque.
    pub const ZERO: Self = Self { force: Vec3::ZERO, torque: Vec3::ZERO };

    /// True when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.force.is_finite() && self.torque.is_finite()
    }

    /// The six components' bits, to compare two commands exactly (−0.0 and 0.0 differ, as in a file).
    pub fn to_bits(&self) -> [u32; 6] {
        [self.force.x, self.force.y, self.force.z, self.torque.x, self.torque.y, self.torque.z].map(f32::to_bits)
    }
}
