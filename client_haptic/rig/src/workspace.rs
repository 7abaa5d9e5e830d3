//! Mapping between the device's workspace frame and the scene.
//!
//! You need this module when the scene is not in device coordinates: the device's point `p` lands at
//! `origin · (scale · p)` in the scene.

use glam::Vec3;
use haptic_common::{ForceTorque, Pose};

/// Device frame (metres) to scene frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorkspaceMap {
    /// Where the device's origin sits in the scene, and how it is turned.
    pub origin: Pose,
    /// Scene units per device metre (default 1).
    pub scale: f32,
}

impl Default for WorkspaceMap {
    fn default() -> Self {
        Self { origin: Pose::IDENTITY, scale: 1.0 }
    }
}

impl WorkspaceMap {
    /// A device pose in scene coordinates.
    #[inline]
    pub fn to_scene(&self, device: &Pose) -> Pose {
        Pose::new(
            self.origin.transform_point(device.translation * self.scale),
            (self.origin.rotation * device.rotation).normalize(),
        )
    }

    /// A scene pose in device coordinates.
    #[inline]
    pub fn to_device(&self, scene: &Pose) -> Pose {
        let local = self.origin.inverse().mul_pose(scene);
        Pose::new(local.translation / self.scale, local.rotation)
    }

    /// A device-frame velocity in scene coordinates.
    #[inline]
    pub fn velocity_to_scene(&self, v: Vec3) -> Vec3 {
        self.origin.rotation * v * self.scale
    }

    /// A device-frame angular velocity in scene coordinates.
    #[inline]
    pub fn angular_velocity_to_scene(&self, w: Vec3) -> Vec3 {
        self.origin.rotation * w
    }

    /// A wrench computed in the scene (torque in N·scene unit) in device coordinates (N, N·m).
    #[inline]
    pub fn wrench_to_device(&self, scene: ForceTorque) -> ForceTorque {
        let inv = self.origin.rotation.inverse();
        ForceTorque { force: inv * scene.force, torque: inv * scene.torque / self.scale }
    }
}

#[cfg(test)]
mod tests {
    use glam::Quat;

    use super::*;

    #[test]
    fn to_device_undoes_to_scene() {
        let map = WorkspaceMap { origin: Pose::new(Vec3::new(1.0, 2.0, 3.0), Quat::from_rotation_y(0.4)), scale: 5.0 };
        let p = Pose::new(Vec3::new(0.01, -0.02, 0.03), Quat::from_rotation_x(0.2));
        let back = map.to_device(&map.to_scene(&p));
        assert!((back.translation - p.translation).length() < 1e-5);
        assert!(back.rotation.angle_between(p.rotation) < 1e-4);
    }

    #[test]
    fn scene_torques_shrink_by_the_scale_on_the_device() {
        let map = WorkspaceMap { scale: 10.0, ..Default::default() };
        let w = map.wrench_to_device(ForceTorque { force: Vec3::X, torque: Vec3::Z });
        assert_eq!(w.force, Vec3::X);
        assert!((w.torque.z - 0.1).abs() < 1e-7);
    }
}
