//! Virtual coupling for 6-DOF rendering: a simulated tool tied to the device by a spring-damper.
//!
//! You need this module when contact forces are stiffer than the device can render stably. The contact
//! force acts on the simulated tool, and the device only ever feels the coupling spring, whose stiffness
//! is chosen within the device's limits, so the loop stays passive (Colgate: b > K·T/2 + |B|, with b the
//! hand's and mechanism's damping, K the coupling stiffness, B the coupling damping, T the period).
//!
//! The tool is integrated implicitly in the coupling terms (unconditionally stable for any stiffness),
//! explicitly in the contact force, which is stabilized by the penalty's own damping and the tool's drag.

use glam::{Quat, Vec3};
use haptic_common::{DeviceState, ForceTorque, Pose};

use crate::error::{Result, non_negative, positive};

/// Parameters of the coupling and the simulated tool.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CouplingConfig {
    /// Coupling stiffness, N/m (default 300; keep below the device's max stiffness).
    pub stiffness_n_per_m: f32,
    /// Coupling damping, N·s/m (default 0.5; keep below the hand's damping minus K·T/2).
    pub damping_ns_per_m: f32,
    /// Rotational coupling stiffness, N·m/rad (default 0.15).
    pub rot_stiffness_nm_per_rad: f32,
    /// Rotational coupling damping, N·m·s/rad (default 0.0005).
    pub rot_damping_nms_per_rad: f32,
    /// Mass of the simulated tool, kg (default 0.05).
    pub tool_mass_kg: f32,
    /// Rotational inertia of the simulated tool, kg·m² (default 2e-5).
    pub tool_inertia_kg_m2: f32,
    /// Drag of the simulated tool against the world, N·s/m (default 2).
    pub tool_drag_ns_per_m: f32,
    /// Rotational drag, N·m·s/rad (default 0.0005).
    pub tool_rot_drag_nms_per_rad: f32,
}

impl Default for CouplingConfig {
    fn default() -> Self {
        Self {
            stiffness_n_per_m: 300.0,
            damping_ns_per_m: 0.5,
            rot_stiffness_nm_per_rad: 0.15,
            rot_damping_nms_per_rad: 0.0005,
            tool_mass_kg: 0.05,
            tool_inertia_kg_m2: 2e-5,
            tool_drag_ns_per_m: 2.0,
            tool_rot_drag_nms_per_rad: 0.0005,
        }
    }
}

impl CouplingConfig {
    /// A coupling for a device: stiffness at 75 % of its max stiffness, damping within the passivity
    /// bound `hand_damping − K·T/2` (halved for margin) and within the device's max damping.
    pub fn for_device(
        max_stiffness_n_per_m: f32,
        max_damping_ns_per_m: f32,
        hand_damping_ns_per_m: f32,
        period_s: f32,
    ) -> Self {
        let k = 0.75 * max_stiffness_n_per_m;
        let bound = (hand_damping_ns_per_m - k * period_s / 2.0).max(0.0);
        Self { stiffness_n_per_m: k, damping_ns_per_m: (0.5 * bound).min(max_damping_ns_per_m), ..Self::default() }
    }

    /// Checks every value.
    pub fn validate(&self) -> Result<()> {
        non_negative("stiffness_n_per_m", self.stiffness_n_per_m)?;
        non_negative("damping_ns_per_m", self.damping_ns_per_m)?;
        non_negative("rot_stiffness_nm_per_rad", self.rot_stiffness_nm_per_rad)?;
        non_negative("rot_damping_nms_per_rad", self.rot_damping_nms_per_rad)?;
        positive("tool_mass_kg", self.tool_mass_kg)?;
        positive("tool_inertia_kg_m2", self.tool_inertia_kg_m2)?;
        non_negative("tool_drag_ns_per_m", self.tool_drag_ns_per_m)?;
        non_negative("tool_rot_drag_nms_per_rad", self.tool_rot_drag_nms_per_rad)
    }
}

/// The simulated tool and its coupling to the device.
#[derive(Clone, Debug)]
pub struct VirtualCoupling {
    config: CouplingConfig,
    pose: Pose,
    v: Vec3,
    w: Vec3,
    started: bool,
}

impl VirtualCoupling {
    /// A coupling whose tool snaps to the device on the first step.
    pub fn new(config: CouplingConfig) -> Self {
        Self { config, pose: Pose::IDENTITY, v: Vec3::ZERO, w: Vec3::ZERO, started: false }
    }

    /// The configuration.
    pub fn config(&self) -> &CouplingConfig {
        &self.config
    }

    /// Pose of the simulated tool (send this to collision detection).
    pub fn tool_pose(&self) -> Pose {
        self.pose
    }

    /// Linear velocity of the tool, m/s.
    pub fn tool_velocity(&self) -> Vec3 {
        self.v
    }

    /// Angular velocity of the tool, rad/s.
    pub fn tool_angular_velocity(&self) -> Vec3 {
        self.w
    }

    /// Puts the tool on the device, at rest relative to it.
    pub fn reset_to(&mut self, device: &DeviceState) {
        self.pose = device.pose;
        self.v = device.linear_velocity;
        self.w = device.angular_velocity;
        self.started = true;
    }

    /// Advances the tool by `dt_s` under the contact force `contact` (on the tool, about its pose origin)
    /// and returns the force and torque to command on the device. Allocation-free; non-finite inputs
    /// leave the tool where it is.
    pub fn step(&mut self, device: &DeviceState, contact: ForceTorque, dt_s: f32) -> ForceTorque {
        if !device.pose.is_finite() || !device.linear_velocity.is_finite() || !device.angular_velocity.is_finite() {
            return ForceTorque::ZERO;
        }
        if !self.started {
            self.reset_to(device);
        }
        let c = self.config;
        let h = if dt_s.is_finite() { dt_s.clamp(0.0, 0.01) } else { 0.0 };
        let env = if contact.is_finite() { contact } else { ForceTorque::ZERO };

        // Linear: implicit Euler in the spring, damper and drag; explicit in the contact force.
        let x = self.pose.translation;
        let xd = device.pose.translation;
        let denom = c.tool_mass_kg + h * (c.damping_ns_per_m + c.tool_drag_ns_per_m) + h * h * c.stiffness_n_per_m;
        self.v = (c.tool_mass_kg * self.v
            + h * (c.stiffness_n_per_m * (xd - x) + c.damping_ns_per_m * device.linear_velocity + env.force))
            / denom;
        self.pose.translation = x + h * self.v;

        // Angular, the same way with the rotation error as a rotation vector.
        let err = rotation_error(device.pose.rotation, self.pose.rotation);
        let denom_r = c.tool_inertia_kg_m2
            + h * (c.rot_damping_nms_per_rad + c.tool_rot_drag_nms_per_rad)
            + h * h * c.rot_stiffness_nm_per_rad;
        self.w = (c.tool_inertia_kg_m2 * self.w
            + h * (c.rot_stiffness_nm_per_rad * err
                + c.rot_damping_nms_per_rad * device.angular_velocity
                + env.torque))
            / denom_r;
        self.pose.rotation = (Quat::from_scaled_axis(self.w * h) * self.pose.rotation).normalize();

        // The device feels the spring pulling it towards the tool.
        let force =
            c.stiffness_n_per_m * (self.pose.translation - xd) + c.damping_ns_per_m * (self.v - device.linear_velocity);
        let err = rotation_error(self.pose.rotation, device.pose.rotation);
        let torque = c.rot_stiffness_nm_per_rad * err + c.rot_damping_nms_per_rad * (self.w - device.angular_velocity);
        let out = ForceTorque { force, torque };
        if out.is_finite() && self.pose.is_finite() {
            out
        } else {
            self.reset_to(device);
            ForceTorque::ZERO
        }
    }
}

/// The rotation vector taking `from` to `to` (shortest way), rad.
fn rotation_error(to: Quat, from: Quat) -> Vec3 {
    let mut q = to * from.inverse();
    if q.w < 0.0 {
        q = -q;
    }
    q.to_scaled_axis()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn device_at(x: Vec3) -> DeviceState {
        DeviceState { pose: Pose::from_translation(x), ..Default::default() }
    }

    #[test]
    fn in_free_space_the_tool_follows_the_device_and_no_force_remains() {
        let mut c = VirtualCoupling::new(CouplingConfig::default());
        c.step(&device_at(Vec3::ZERO), ForceTorque::ZERO, 0.001);
        let mut out = ForceTorque::ZERO;
        for _ in 0..3000 {
            out = c.step(&device_at(Vec3::new(0.01, 0.0, 0.0)), ForceTorque::ZERO, 0.001);
        }
        assert!((c.tool_pose().translation.x - 0.01).abs() < 1e-5);
        assert!(out.force.length() < 1e-3);
    }

    #[test]
    fn a_held_contact_force_is_passed_to_the_device_through_the_spring() {
        let mut c = VirtualCoupling::new(CouplingConfig::default());
        let mut out = ForceTorque::ZERO;
        for _ in 0..5000 {
            out = c.step(
                &device_at(Vec3::ZERO),
                ForceTorque { force: Vec3::new(0.0, 0.0, 2.0), torque: Vec3::ZERO },
                0.001,
            );
        }
        // At rest: k (x_tool - x_dev) = F_contact, the device feels +2 N.
        assert!((out.force.z - 2.0).abs() < 1e-3, "{:?}", out.force);
        assert!((c.tool_pose().translation.z - 2.0 / 300.0).abs() < 1e-5);
    }

    #[test]
    fn a_rotated_device_drags_the_tool_round() {
        let mut c = VirtualCoupling::new(CouplingConfig::default());
        c.step(&device_at(Vec3::ZERO), ForceTorque::ZERO, 0.001);
        let target = Quat::from_rotation_z(0.5);
        for _ in 0..5000 {
            c.step(
                &DeviceState { pose: Pose::new(Vec3::ZERO, target), ..Default::default() },
                ForceTorque::ZERO,
                0.001,
            );
        }
        assert!(c.tool_pose().rotation.angle_between(target) < 1e-3);
    }

    #[test]
    fn the_default_for_a_touch_respects_the_passivity_bound() {
        let c = CouplingConfig::for_device(400.0, 2.0, 4.0, 0.001);
        assert!(c.stiffness_n_per_m <= 400.0);
        assert!(4.0 > c.stiffness_n_per_m * 0.001 / 2.0 + c.damping_ns_per_m);
    }

    #[test]
    fn non_finite_contact_forces_are_ignored() {
        let mut c = VirtualCoupling::new(CouplingConfig::default());
        let out =
            c.step(&device_at(Vec3::ZERO), ForceTorque { force: Vec3::splat(f32::NAN), torque: Vec3::ZERO }, 0.001);
        assert!(out.is_finite());
        assert!(c.tool_pose().is_finite());
    }
}
