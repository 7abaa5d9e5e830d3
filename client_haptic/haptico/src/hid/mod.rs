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

mod pid;
mod spacemouse;

pub use pid::{
    PidForceDevice, PidReportIds, encode_constant_force, encode_effect_operation, encode_set_effect, pid_force,
};
pub use spacemouse::{SpaceMouse, SpaceMouseAxes, SpaceMouseMode, spacemouse_pose, spacemouse_specs};

use crate::{HapticoError, Result};

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

pub(crate) fn hid_err(e: hidapi::HidError) -> HapticoError {
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

pub(crate) fn open_first(
    kind: HidKind,
    wanted: &str,
    path: Option<&str>,
) -> Result<(hidapi::HidDevice, HidDeviceInfo)> {
    let api = hidapi::HidApi::new().map_err(hid_err)?;
    let found = api.device_list().find(|d| {
        classify(d.vendor_id(), d.usage_page(), d.usage()) == kind
            && path.is_none_or(|p| d.path().to_string_lossy() == p)
    });
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::HapticoError;

    #[test]
    fn spacemouse_and_pid_interfaces_are_recognized_by_usage() {
        assert_eq!(classify(VID_3DCONNEXION, 0x01, 0x08), HidKind::SixDofInput);
        assert_eq!(classify(VID_LOGITECH, 0x01, 0x08), HidKind::SixDofInput);
        assert_eq!(classify(0x1234, 0x0F, 0x01), HidKind::ForceFeedback);
        assert_eq!(classify(0x1234, 0x01, 0x06), HidKind::Other);
    }

    #[test]
    fn listing_without_devices_is_not_an_error_storm() {
        // On CI there is no HID device (and maybe no hidraw at all): either an empty list or one clear error.
        match list_devices() {
            Ok(list) => assert!(list.iter().all(|d| !d.path.is_empty())),
            Err(e) => assert!(!e.to_string().is_empty()),
        }
        if let Err(e) =
            SpaceMouse::open_first(SpaceMouseMode::Rate { metres_per_s_per_count: 1e-4, radians_per_s_per_count: 1e-3 })
        {
            assert!(matches!(e, HapticoError::NoDevice { .. } | HapticoError::Hid(_)), "{e}");
        }
    }
}
