//! The 3Dconnexion SpaceMouse as a 6-DOF input device (position or rate control).

use glam::{Quat, Vec3};
use haptic_common::{Buttons, DeviceState, ForceTorque, Pose};

use super::{HidDeviceInfo, HidKind, open_first};
use crate::{Device, DeviceSpecs, Result};

/// How SpaceMouse deflection becomes a pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpaceMouseMode {
    /// Deflection maps to an offset from the origin: metres and radians per count.
    Position {
        /// m per count (default-ish 1e-4: ±350 counts → ±35 mm).
        metres_per_count: f32,
        /// rad per count.
        radians_per_count: f32,
    },
    /// Deflection sets a velocity that is integrated (joystick style).
    Rate {
        /// m/s per count.
        metres_per_s_per_count: f32,
        /// rad/s per count.
        radians_per_s_per_count: f32,
    },
}

/// Raw SpaceMouse axes and buttons, updated by input reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpaceMouseAxes {
    /// Translation counts (x, y, z).
    pub translation: [i16; 3],
    /// Rotation counts (rx, ry, rz).
    pub rotation: [i16; 3],
    /// Buttons bit set.
    pub buttons: u32,
}

impl SpaceMouseAxes {
    /// Applies one input report (report id in byte 0): id 1 carries translation (and rotation on newer
    /// models, 13 bytes), id 2 rotation, id 3 buttons. Returns false for unknown reports.
    pub fn apply_report(&mut self, report: &[u8]) -> bool {
        let axes = |bytes: &[u8]| -> [i16; 3] {
            [
                i16::from_le_bytes([bytes[0], bytes[1]]),
                i16::from_le_bytes([bytes[2], bytes[3]]),
                i16::from_le_bytes([bytes[4], bytes[5]]),
            ]
        };
        match report {
            [1, rest @ ..] if rest.len() >= 12 => {
                self.translation = axes(&rest[..6]);
                self.rotation = axes(&rest[6..12]);
                true
            }
            [1, rest @ ..] if rest.len() >= 6 => {
                self.translation = axes(&rest[..6]);
                true
            }
            [2, rest @ ..] if rest.len() >= 6 => {
                self.rotation = axes(&rest[..6]);
                true
            }
            [3, rest @ ..] if !rest.is_empty() => {
                let mut b = [0u8; 4];
                let n = rest.len().min(4);
                b[..n].copy_from_slice(&rest[..n]);
                self.buttons = u32::from_le_bytes(b);
                true
            }
            _ => false,
        }
    }
}

/// Specs of a SpaceMouse: 6-DOF sensed, nothing actuated.
pub fn spacemouse_specs() -> DeviceSpecs {
    DeviceSpecs {
        name: "3Dconnexion SpaceMouse",
        sensed_dof: 6,
        actuated_dof: 0,
        peak_force_n: 0.0,
        continuous_force_n: 0.0,
        max_torque_nm: 0.0,
        max_stiffness_n_per_m: 0.0,
        max_damping_ns_per_m: 0.0,
        workspace_radius_m: 0.1,
    }
}

/// A SpaceMouse as an input-only device.
pub struct SpaceMouse {
    device: hidapi::HidDevice,
    info: HidDeviceInfo,
    specs: DeviceSpecs,
    mode: SpaceMouseMode,
    axes: SpaceMouseAxes,
    pose: Pose,
    last_t_us: Option<u64>,
    read_errors: u64,
    buf: [u8; 64],
}

impl std::fmt::Debug for SpaceMouse {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpaceMouse").field("info", &self.info).field("mode", &self.mode).finish_non_exhaustive()
    }
}

impl SpaceMouse {
    /// Opens the first SpaceMouse found.
    pub fn open_first(mode: SpaceMouseMode) -> Result<Self> {
        Self::open(mode, None)
    }

    /// Like [`SpaceMouse::open_first`], but only the interface at hidraw `path` when given.
    pub fn open(mode: SpaceMouseMode, path: Option<&str>) -> Result<Self> {
        let (device, info) = open_first(HidKind::SixDofInput, "3Dconnexion SpaceMouse", path)?;
        Ok(Self {
            device,
            info,
            specs: spacemouse_specs(),
            mode,
            axes: SpaceMouseAxes::default(),
            pose: Pose::IDENTITY,
            last_t_us: None,
            read_errors: 0,
            buf: [0; 64],
        })
    }

    /// The interface opened.
    pub fn info(&self) -> &HidDeviceInfo {
        &self.info
    }

    /// Failed reads so far (the device keeps its last state on a failed read).
    pub fn read_errors(&self) -> u64 {
        self.read_errors
    }
}

/// Integrates or maps SpaceMouse axes into a pose and velocity; pure, so it is tested without hardware.
pub fn spacemouse_pose(mode: SpaceMouseMode, axes: &SpaceMouseAxes, previous: Pose, dt_s: f32) -> (Pose, Vec3, Vec3) {
    let t = Vec3::new(axes.translation[0] as f32, axes.translation[1] as f32, axes.translation[2] as f32);
    let r = Vec3::new(axes.rotation[0] as f32, axes.rotation[1] as f32, axes.rotation[2] as f32);
    match mode {
        SpaceMouseMode::Position { metres_per_count, radians_per_count } => {
            let pose = Pose::new(t * metres_per_count, Quat::from_scaled_axis(r * radians_per_count));
            let v = if dt_s > 0.0 { (pose.translation - previous.translation) / dt_s } else { Vec3::ZERO };
            (pose, v, Vec3::ZERO)
        }
        SpaceMouseMode::Rate { metres_per_s_per_count, radians_per_s_per_count } => {
            let v = t * metres_per_s_per_count;
            let w = r * radians_per_s_per_count;
            let pose = Pose::new(
                previous.translation + v * dt_s,
                (Quat::from_scaled_axis(w * dt_s) * previous.rotation).normalize(),
            );
            (pose, v, w)
        }
    }
}

impl Device for SpaceMouse {
    fn specs(&self) -> &DeviceSpecs {
        &self.specs
    }

    fn read_state(&mut self, t_us: u64) -> DeviceState {
        // Drain every pending report without blocking.
        loop {
            match self.device.read_timeout(&mut self.buf, 0) {
                Ok(0) => break,
                Ok(n) => {
                    let report = &self.buf[..n];
                    let mut axes = self.axes;
                    axes.apply_report(report);
                    self.axes = axes;
                }
                Err(_) => {
                    self.read_errors += 1;
                    break;
                }
            }
        }
        let dt = self.last_t_us.map_or(0.0, |l| t_us.saturating_sub(l) as f32 * 1e-6);
        self.last_t_us = Some(t_us);
        let (pose, v, w) = spacemouse_pose(self.mode, &self.axes, self.pose, dt);
        self.pose = pose;
        DeviceState {
            pose,
            linear_velocity: v,
            angular_velocity: w,
            buttons: Buttons(self.axes.buttons),
            timestamp_us: t_us,
        }
    }

    fn command(&mut self, _ft: ForceTorque) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spacemouse_reports_update_axes_and_buttons() {
        let mut a = SpaceMouseAxes::default();
        assert!(a.apply_report(&[1, 10, 0, 0xF6, 0xFF, 0, 1]));
        assert_eq!(a.translation, [10, -10, 256]);
        assert!(a.apply_report(&[2, 1, 0, 2, 0, 3, 0]));
        assert_eq!(a.rotation, [1, 2, 3]);
        assert!(a.apply_report(&[3, 0b101]));
        assert_eq!(a.buttons, 0b101);
        let mut b = SpaceMouseAxes::default();
        assert!(b.apply_report(&[1, 1, 0, 2, 0, 3, 0, 4, 0, 5, 0, 6, 0]));
        assert_eq!((b.translation, b.rotation), ([1, 2, 3], [4, 5, 6]));
        assert!(!b.apply_report(&[9, 1, 2]));
    }

    #[test]
    fn rate_control_integrates_and_position_control_maps() {
        let axes = SpaceMouseAxes { translation: [100, 0, 0], ..Default::default() };
        let rate = SpaceMouseMode::Rate { metres_per_s_per_count: 1e-3, radians_per_s_per_count: 0.0 };
        let (p, v, _) = spacemouse_pose(rate, &axes, Pose::IDENTITY, 0.5);
        assert!((p.translation.x - 0.05).abs() < 1e-6 && (v.x - 0.1).abs() < 1e-6);
        let pos = SpaceMouseMode::Position { metres_per_count: 1e-4, radians_per_count: 0.0 };
        let (p, _, _) = spacemouse_pose(pos, &axes, Pose::IDENTITY, 0.001);
        assert!((p.translation.x - 0.01).abs() < 1e-6);
    }
}
