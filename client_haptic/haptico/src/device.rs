//! The [`Device`] trait every backend implements, and the [`DeviceSpecs`] that the safety layer uses.
//!
//! You need this module to write a backend for a new device, or to read a device's limits.

use haptic_common::{DeviceState, ForceTorque};

/// Limits and capabilities of a haptic device (values from the makers' and CHAI3D's public tables).
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceSpecs {
    /// Model name.
    pub name: &'static str,
    /// Degrees of freedom sensed (3 = position, 6 = position + orientation).
    pub sensed_dof: u8,
    /// Degrees of freedom actuated (3 = force only, 6 = force + torque, 0 = input only).
    pub actuated_dof: u8,
    /// Peak force, N.
    pub peak_force_n: f32,
    /// Continuous (sustainable) force, N.
    pub continuous_force_n: f32,
    /// Maximum torque, N·m (0 when torque is not actuated).
    pub max_torque_nm: f32,
    /// Highest stable rendering stiffness, N/m.
    pub max_stiffness_n_per_m: f32,
    /// Highest stable rendering damping, N·s/m.
    pub max_damping_ns_per_m: f32,
    /// Radius of the workspace sphere, m.
    pub workspace_radius_m: f32,
}

impl DeviceSpecs {
    /// True when the device can render torques.
    pub fn renders_torque(&self) -> bool {
        self.actuated_dof >= 6 && self.max_torque_nm > 0.0
    }

    /// Clamps a command to the peak force and torque, zeroes non-finite values and unactuated torque.
    /// The haptic thread applies this to every command, whatever the force layer did before.
    #[inline]
    pub fn clamp(&self, ft: ForceTorque) -> ForceTorque {
        let force = if ft.force.is_finite() && self.actuated_dof > 0 {
            ft.force.clamp_length_max(self.peak_force_n)
        } else {
            glam::Vec3::ZERO
        };
        let torque = if ft.torque.is_finite() && self.renders_torque() {
            ft.torque.clamp_length_max(self.max_torque_nm)
        } else {
            glam::Vec3::ZERO
        };
        ForceTorque { force, torque }
    }
}

/// A haptic device (or anything that samples a pose and takes force commands).
///
/// Called from the haptic thread only: implementations must not allocate, lock or log in
/// `read_state` and `command` once running.
pub trait Device: Send {
    /// The device's limits.
    fn specs(&self) -> &DeviceSpecs;
    /// Samples the end effector; `t_us` is the haptic clock's time of this tick (the device does not read a clock).
    fn read_state(&mut self, t_us: u64) -> DeviceState;
    /// Commands a force and torque, held until the next command.
    fn command(&mut self, ft: ForceTorque);
    /// Called once when the haptic thread stops: leave the device without force.
    fn release(&mut self) {
        self.command(ForceTorque::ZERO);
    }
}

impl<D: Device + ?Sized> Device for Box<D> {
    fn specs(&self) -> &DeviceSpecs {
        (**self).specs()
    }
    fn read_state(&mut self, t_us: u64) -> DeviceState {
        (**self).read_state(t_us)
    }
    fn command(&mut self, ft: ForceTorque) {
        (**self).command(ft)
    }
    fn release(&mut self) {
        (**self).release()
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::presets;

    #[test]
    fn clamp_caps_force_and_drops_torque_on_a_three_dof_device() {
        let specs = presets::touch();
        let out = specs.clamp(ForceTorque { force: Vec3::new(10.0, 0.0, 0.0), torque: Vec3::X });
        assert!((out.force.length() - specs.peak_force_n).abs() < 1e-5);
        assert_eq!(out.torque, Vec3::ZERO);
    }

    #[test]
    fn clamp_turns_non_finite_commands_into_zero() {
        let specs = presets::phantom_premium_6dof();
        let out = specs.clamp(ForceTorque { force: Vec3::new(f32::NAN, 0.0, 0.0), torque: Vec3::splat(f32::INFINITY) });
        assert_eq!(out, ForceTorque::ZERO);
    }
}
