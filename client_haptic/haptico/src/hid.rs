//! HID devices through hidapi: listing, a 3Dconnexion SpaceMouse as a 6-DOF input device, and HID PID
//! force-feedback devices (joysticks, wheels) as force output through a constant-force effect.
//!
//! You need this module to use consumer hardware without a vendor SDK. Neither kind is a true haptic
//! device: a SpaceMouse only senses (position or rate control), and a PID device renders a coarse
//! force on one or two axes. When nothing is connected, the `open_*` functions return
//! [`HapticoError::NoDevice`] once, with a hint; they never retry in a loop.
//!
//! # Linux permissions
//! hidraw nodes belong to root. Install a udev rule, e.g. `/etc/udev/rules.d/70-haptico.rules`:
//! ```text
//! # 3Dconnexion (old Logitech and current vendor ids)
//! KERNEL=="hidraw*", ATTRS{idVendor}=="256f", MODE="0660", TAG+="uaccess"
//! KERNEL=="hidraw*", ATTRS{idVendor}=="046d", ATTRS{idProduct}=="c6[0-2]?", MODE="0660", TAG+="uaccess"
//! ```
//! then `sudo udevadm control --reload-rules && sudo udevadm trigger`, and replug the device.
//! Building needs `libudev-dev` (and `pkg-config`).
//!
//! The PID report ids below follow the example descriptor of the USB HID PID 1.0 specification; many
//! devices use them, but some do not (read your device's report descriptor). Tested against no hardware.

use glam::{Quat, Vec3};
use haptic_common::{Buttons, DeviceState, ForceTorque, Pose};

use crate::{Device, DeviceSpecs, HapticoError, Result};

/// HID usage page "Generic Desktop".
pub const USAGE_PAGE_GENERIC_DESKTOP: u16 = 0x01;
/// Usage "Multi-axis Controller" (SpaceMouse and friends).
pub const USAGE_MULTI_AXIS_CONTROLLER: u16 = 0x08;
/// HID usage page "Physical Interface Device" (force feedback).
pub const USAGE_PAGE_PID: u16 = 0x0F;
/// 3Dconnexion's vendor id.
pub const VID_3DCONNEXION: u16 = 0x256F;
/// Logitech's vendor id (older 3Dconnexion devices).
pub const VID_LOGITECH: u16 = 0x046D;

const UDEV_HINT: &str = "connect one, and on Linux check the udev rule in haptico::hid's docs (hidraw permissions)";

/// What a HID device looks like to us.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HidKind {
    /// A 6-DOF input device (SpaceMouse).
    SixDofInput,
    /// A force-feedback device (HID PID usage page).
    ForceFeedback,
    /// Anything else.
    Other,
}

/// One HID interface found by [`list_devices`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HidDeviceInfo {
    /// Vendor id.
    pub vendor_id: u16,
    /// Product id.
    pub product_id: u16,
    /// Top-level usage page.
    pub usage_page: u16,
    /// Top-level usage.
    pub usage: u16,
    /// Product name, if the device gives one.
    pub product: String,
    /// Platform path, for opening.
    pub path: String,
    /// Our classification.
    pub kind: HidKind,
}

/// Classifies an interface from its ids and top-level usage.
pub fn classify(vendor_id: u16, usage_page: u16, usage: u16) -> HidKind {
    if usage_page == USAGE_PAGE_PID {
        HidKind::ForceFeedback
    } else if usage_page == USAGE_PAGE_GENERIC_DESKTOP
        && usage == USAGE_MULTI_AXIS_CONTROLLER
        && (vendor_id == VID_3DCONNEXION || vendor_id == VID_LOGITECH)
    {
        HidKind::SixDofInput
    } else {
        HidKind::Other
    }
}

fn hid_err(e: hidapi::HidError) -> HapticoError {
    HapticoError::Hid(e.to_string())
}

/// Every HID interface the system shows us.
pub fn list_devices() -> Result<Vec<HidDeviceInfo>> {
    let api = hidapi::HidApi::new().map_err(hid_err)?;
    Ok(api
        .device_list()
        .map(|d| HidDeviceInfo {
            vendor_id: d.vendor_id(),
            product_id: d.product_id(),
            usage_page: d.usage_page(),
            usage: d.usage(),
            product: d.product_string().unwrap_or("").to_owned(),
            path: d.path().to_string_lossy().into_owned(),
            kind: classify(d.vendor_id(), d.usage_page(), d.usage()),
        })
        .collect())
}

fn open_first(kind: HidKind, wanted: &str) -> Result<(hidapi::HidDevice, HidDeviceInfo)> {
    let api = hidapi::HidApi::new().map_err(hid_err)?;
    let found = api.device_list().find(|d| classify(d.vendor_id(), d.usage_page(), d.usage()) == kind);
    let Some(info) = found else {
        return Err(HapticoError::NoDevice { wanted: wanted.into(), hint: UDEV_HINT.into() });
    };
    let device = api.open_path(info.path()).map_err(|e| HapticoError::Hid(format!("{e} ({UDEV_HINT})")))?;
    device.set_blocking_mode(false).map_err(hid_err)?;
    let info = HidDeviceInfo {
        vendor_id: info.vendor_id(),
        product_id: info.product_id(),
        usage_page: info.usage_page(),
        usage: info.usage(),
        product: info.product_string().unwrap_or("").to_owned(),
        path: info.path().to_string_lossy().into_owned(),
        kind,
    };
    Ok((device, info))
}

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
        let (device, info) = open_first(HidKind::SixDofInput, "3Dconnexion SpaceMouse")?;
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
        DeviceState { pose, linear_velocity: v, angular_velocity: w, buttons: Buttons(self.axes.buttons), timestamp_us: t_us }
    }

    fn command(&mut self, _ft: ForceTorque) {}
}

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
        ids.set_effect, block, EFFECT_TYPE_CONSTANT, dur[0], dur[1], // duration
        0, 0, // trigger repeat interval
        0, 0, // sample period (default)
        255, // gain
        0xFF, // trigger button: none
        0b11, // axes enable X, Y
        dir[0], dir[1],
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
        let (device, info) = open_first(HidKind::ForceFeedback, "HID PID force-feedback device")?;
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
    fn spacemouse_and_pid_interfaces_are_recognized_by_usage() {
        assert_eq!(classify(VID_3DCONNEXION, 0x01, 0x08), HidKind::SixDofInput);
        assert_eq!(classify(VID_LOGITECH, 0x01, 0x08), HidKind::SixDofInput);
        assert_eq!(classify(0x1234, 0x0F, 0x01), HidKind::ForceFeedback);
        assert_eq!(classify(0x1234, 0x01, 0x06), HidKind::Other);
    }

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

    #[test]
    fn listing_without_devices_is_not_an_error_storm() {
        // On CI there is no HID device (and maybe no hidraw at all): either an empty list or one clear error.
        match list_devices() {
            Ok(list) => assert!(list.iter().all(|d| !d.path.is_empty())),
            Err(e) => assert!(!e.to_string().is_empty()),
        }
        if let Err(e) = SpaceMouse::open_first(SpaceMouseMode::Rate { metres_per_s_per_count: 1e-4, radians_per_s_per_count: 1e-3 }) {
            assert!(matches!(e, HapticoError::NoDevice { .. } | HapticoError::Hid(_)), "{e}");
        }
    }
}
