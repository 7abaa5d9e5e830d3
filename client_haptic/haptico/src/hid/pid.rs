//! HID PID force-feedback devices driven through one constant-force effect.

use glam::Vec3;
use haptic_common::{DeviceState, ForceTorque};

use super::{HidDeviceInfo, HidKind, hid_err, open_first};
use crate::{Device, DeviceSpecs, Result};

/// Report ids of a HID PID device (defaults: the PID 1.0 specification's example descriptor).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PidReportIds {
    /// Output "Set Effect" (default 0x01).
    pub set_effect: u8,
    /// Output "Set Constant Force" (default 0x05).
    pub set_constant_force: u8,
    /// Output "Effect Operation" (default 0x0A).
    pub effect_operation: u8,
    /// Output "Device Control" (default 0x0C).
    pub device_control: u8,
}

impl Default for PidReportIds {
    fn default() -> Self {
        Self { set_effect: 0x01, set_constant_force: 0x05, effect_operation: 0x0A, device_control: 0x0C }
    }
}

/// Effect type "constant force" in the PID usage table's order (ET Constant Force = 1).
const EFFECT_TYPE_CONSTANT: u8 = 1;

/// Encodes "Set Constant Force": block index, magnitude −10000..=10000 (little-endian i16).
pub fn encode_constant_force(ids: &PidReportIds, block: u8, magnitude: i16) -> [u8; 4] {
    let m = magnitude.clamp(-10_000, 10_000).to_le_bytes();
    [ids.set_constant_force, block, m[0], m[1]]
}

/// Encodes "Set Effect" for an endless constant-force effect on X and Y in `direction_cdeg`
/// (hundredths of a degree, 0 = +Y), full gain.
pub fn encode_set_effect(ids: &PidReportIds, block: u8, direction_cdeg: u16) -> [u8; 14] {
    let dur = 0xFFFFu16.to_le_bytes(); // infinite
    let dir = direction_cdeg.to_le_bytes();
    [
        ids.set_effect,
        block,
        EFFECT_TYPE_CONSTANT,
        dur[0],
        dur[1], // duration
        0,
        0, // trigger repeat interval
        0,
        0,    // sample period (default)
        255,  // gain
        0xFF, // trigger button: none
        0b11, // axes enable X, Y
        dir[0],
        dir[1],
    ]
}

/// Encodes "Effect Operation": start (1) or stop (3) the effect in `block`.
pub fn encode_effect_operation(ids: &PidReportIds, block: u8, start: bool) -> [u8; 4] {
    [ids.effect_operation, block, if start { 1 } else { 3 }, if start { 1 } else { 0 }]
}

/// Maps a planar force (x, y; N) to a PID direction (centi-degrees, 0 = +Y, clockwise) and magnitude
/// (−10000..=10000 of the device's `peak_force_n`).
pub fn pid_force(force: Vec3, peak_force_n: f32) -> (u16, i16) {
    let planar = Vec3::new(force.x, force.y, 0.0);
    let len = planar.length();
    if !len.is_finite() || len <= 0.0 || peak_force_n <= 0.0 {
        return (0, 0);
    }
    let angle = force.x.atan2(force.y).to_degrees().rem_euclid(360.0);
    let magnitude = ((len / peak_force_n).min(1.0) * 10_000.0) as i16;
    ((angle * 100.0) as u16 % 36_000, magnitude)
}

/// A HID PID force-feedback device: forces go out as one constant-force effect; it senses nothing
/// (pair it with an input device in your own `Device` if needed).
pub struct PidForceDevice {
    device: hidapi::HidDevice,
    info: HidDeviceInfo,
    specs: DeviceSpecs,
    ids: PidReportIds,
    block: u8,
    last_sent: (u16, i16),
    write_errors: u64,
}

impl std::fmt::Debug for PidForceDevice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PidForceDevice").field("info", &self.info).finish_non_exhaustive()
    }
}

impl PidForceDevice {
    /// Opens the first PID device, creates and starts a constant-force effect in block 1 at zero force.
    /// `peak_force_n` is what full magnitude means on this device (not published by the device itself).
    pub fn open_first(ids: PidReportIds, peak_force_n: f32) -> Result<Self> {
        Self::open(ids, peak_force_n, None)
    }

    /// Like [`PidForceDevice::open_first`], but only the interface at hidraw `path` (e.g. `/dev/hidraw3`) when given.
    pub fn open(ids: PidReportIds, peak_force_n: f32, path: Option<&str>) -> Result<Self> {
        let (device, info) = open_first(HidKind::ForceFeedback, "HID PID force-feedback device", path)?;
        let block = 1;
        device.write(&[ids.device_control, 0x01]).map_err(hid_err)?; // enable actuators
        device.write(&encode_set_effect(&ids, block, 0)).map_err(hid_err)?;
        device.write(&encode_constant_force(&ids, block, 0)).map_err(hid_err)?;
        device.write(&encode_effect_operation(&ids, block, true)).map_err(hid_err)?;
        let specs = DeviceSpecs {
            name: "HID PID force-feedback device",
            sensed_dof: 0,
            actuated_dof: 2,
            peak_force_n,
            continuous_force_n: peak_force_n,
            max_torque_nm: 0.0,
            max_stiffness_n_per_m: 0.0,
            max_damping_ns_per_m: 0.0,
            workspace_radius_m: 0.0,
        };
        Ok(Self { device, info, specs, ids, block, last_sent: (0, 0), write_errors: 0 })
    }

    /// The interface opened.
    pub fn info(&self) -> &HidDeviceInfo {
        &self.info
    }

    /// Failed writes so far.
    pub fn write_errors(&self) -> u64 {
        self.write_errors
    }
}

impl Device for PidForceDevice {
    fn specs(&self) -> &DeviceSpecs {
        &self.specs
    }

    fn read_state(&mut self, t_us: u64) -> DeviceState {
        DeviceState { timestamp_us: t_us, ..Default::default() }
    }

    fn command(&mut self, ft: ForceTorque) {
        let (dir, mag) = pid_force(ft.force, self.specs.peak_force_n);
        // Only talk to the device when something changed noticeably (USB bandwidth).
        if dir.abs_diff(self.last_sent.0) < 100 && mag.abs_diff(self.last_sent.1) < 50 {
            return;
        }
        let ok = self.device.write(&encode_set_effect(&self.ids, self.block, dir)).is_ok()
            && self.device.write(&encode_constant_force(&self.ids, self.block, mag)).is_ok();
        if ok {
            self.last_sent = (dir, mag);
        } else {
            self.write_errors += 1;
        }
    }

    fn release(&mut self) {
        let _ = self.device.write(&encode_constant_force(&self.ids, self.block, 0));
        let _ = self.device.write(&encode_effect_operation(&self.ids, self.block, false));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pid_reports_carry_direction_and_bounded_magnitude() {
        let ids = PidReportIds::default();
        let (dir, mag) = pid_force(Vec3::new(1.0, 0.0, 0.0), 2.0);
        assert_eq!((dir, mag), (9000, 5000));
        let (_, mag) = pid_force(Vec3::new(0.0, -50.0, 0.0), 2.0);
        assert_eq!(mag, 10_000);
        assert_eq!(pid_force(Vec3::splat(f32::NAN), 2.0), (0, 0));
        assert_eq!(encode_constant_force(&ids, 1, -20_000), [0x05, 1, 0xF0, 0xD8]);
        assert_eq!(encode_effect_operation(&ids, 1, true), [0x0A, 1, 1, 1]);
        assert_eq!(encode_set_effect(&ids, 1, 9000)[12..], [0x28, 0x23]);
    }
}
