//! Naming and opening a device: `sim`, `trace:FILE`, `hid[:PATH]`, `falcon[:FIRMWARE]`, `haply[:URL]`
//! ([`DeviceChoice`], parsed from those names), and [`open`], which gives the device for the haptic
//! thread, the hand that steers a simulated one, and the link to watch for a real one.
//!
//! You need this module to let a user choose a device by name (a command line, a settings file) without
//! knowing each backend's opening call.

use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Arc;

use glam::{Quat, Vec3};
use haptic_common::Pose;

use crate::steer::{HandControl, SteeredSim};
use crate::{Device, DeviceSpecs};

/// A device, by name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceChoice {
    /// A simulated device steered through a [`HandControl`] (`sim`).
    Sim,
    /// Replays a recorded trace (haptico's CSV format), looping (`trace:FILE`).
    Trace(PathBuf),
    /// A HID device: the first HID PID force-feedback device or SpaceMouse, or the one at hidraw `PATH`
    /// (`hid[:PATH]`).
    Hid(Option<String>),
    /// The first Novint Falcon on USB, loading Novint's firmware from `FIRMWARE` when it is not running
    /// (`falcon[:FIRMWARE]`).
    Falcon(Option<PathBuf>),
    /// The first Haply Inverse3 of the Haply Inverse Service at `URL`, a WebSocket address
    /// (`haply[:URL]`).
    Haply(String),
}

impl FromStr for DeviceChoice {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.split_once(':') {
            None if s == "sim" => Ok(Self::Sim),
            None if s == "hid" => Ok(Self::Hid(None)),
            None if s == "falcon" => Ok(Self::Falcon(None)),
            None if s == "haply" => Ok(Self::Haply(HAPLY_URL.to_owned())),
            Some(("haply", url)) if !url.is_empty() => Ok(Self::Haply(url.to_owned())),
            Some(("falcon", file)) if !file.is_empty() => Ok(Self::Falcon(Some(PathBuf::from(file)))),
            Some(("trace", file)) if !file.is_empty() => Ok(Self::Trace(PathBuf::from(file))),
            Some(("hid", path)) if !path.is_empty() => Ok(Self::Hid(Some(path.to_owned()))),
            _ => {
                Err(format!("{s:?} is not a device: use sim, trace:FILE, hid[:PATH], falcon[:FIRMWARE] or haply[:URL]"))
            }
        }
    }
}

/// The Haply Inverse Service's default address.
#[cfg(feature = "haply")]
const HAPLY_URL: &str = crate::haply::DEFAULT_URL;
#[cfg(not(feature = "haply"))]
const HAPLY_URL: &str = "ws://localhost:10001/";

/// What a real device's I/O thread tells of its link, to watch while it runs.
#[derive(Clone, Debug, Default)]
pub enum DeviceLink {
    /// A device with no link to lose (simulated, a trace, HID).
    #[default]
    Local,
    /// The Falcon's USB link and homing.
    #[cfg(feature = "falcon")]
    Falcon(Arc<crate::falcon::device::FalconStatus>),
    /// The Haply Inverse Service's connection.
    #[cfg(feature = "haply")]
    Haply(Arc<crate::haply::HaplyStatus>),
}

/// A device opened for the haptic thread.
pub struct Opened {
    /// The device.
    pub device: Box<dyn Device>,
    /// With `sim`: what moves its hand.
    pub hand: Option<HandControl>,
    /// Its link, to watch.
    pub link: DeviceLink,
}

/// Why a device could not be opened (one line, saying what to check).
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// The trace could not be read or replayed.
    #[error("the trace {path}: {reason}")]
    Trace {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        reason: String,
    },
    /// No HID device could be opened.
    #[error("no HID device: {0}")]
    Hid(String),
    /// The Falcon could not be opened.
    #[error("the Falcon: {0}")]
    Falcon(String),
    /// The Inverse3 could not be reached.
    #[error("the Haply Inverse3: {0}")]
    Haply(String),
    /// This build leaves the backend out.
    #[error("this build of haptico has no {0} support (its `{0}` feature)")]
    NotBuilt(&'static str),
}

/// Opens the chosen device. `specs` are the limits of a simulated, replayed or HID device (a Falcon and
/// an Inverse3 bring their own); a simulated hand rests at `start`, an Inverse3 is centred there
/// (device frame, m).
pub fn open(choice: &DeviceChoice, specs: DeviceSpecs, start: Vec3) -> Result<Opened, OpenError> {
    let local = |device: Box<dyn Device>, hand| Opened { device, hand, link: DeviceLink::Local };
    match choice {
        DeviceChoice::Sim => {
            let (device, control) = SteeredSim::new(specs, Pose::new(start, Quat::IDENTITY));
            Ok(local(Box::new(device), Some(control)))
        }
        DeviceChoice::Trace(path) => {
            let failed = |reason: String| OpenError::Trace { path: path.clone(), reason };
            let samples = crate::trace::load(path).map_err(|e| failed(format!("reading it: {e}")))?;
            let device = crate::trace::TraceDevice::new(specs, samples, true).map_err(|e| failed(e.to_string()))?;
            Ok(local(Box::new(device), None))
        }
        DeviceChoice::Hid(path) => open_hid(path.as_deref(), &specs).map(|d| local(d, None)),
        DeviceChoice::Falcon(firmware) => open_falcon(firmware.as_deref()),
        DeviceChoice::Haply(url) => open_haply(url, start),
    }
}

#[cfg(feature = "falcon")]
fn open_falcon(firmware: Option<&std::path::Path>) -> Result<Opened, OpenError> {
    let (device, status) = crate::falcon::open(firmware).map_err(|e| OpenError::Falcon(e.to_string()))?;
    Ok(Opened { device: Box::new(device), hand: None, link: DeviceLink::Falcon(status) })
}

#[cfg(not(feature = "falcon"))]
fn open_falcon(_: Option<&std::path::Path>) -> Result<Opened, OpenError> {
    Err(OpenError::NotBuilt("falcon"))
}

#[cfg(feature = "haply")]
fn open_haply(url: &str, start: Vec3) -> Result<Opened, OpenError> {
    let (device, status) =
        crate::haply::open(url, crate::presets::inverse3(), start).map_err(|e| OpenError::Haply(e.to_string()))?;
    Ok(Opened { device: Box::new(device), hand: None, link: DeviceLink::Haply(status) })
}

#[cfg(not(feature = "haply"))]
fn open_haply(_: &str, _: Vec3) -> Result<Opened, OpenError> {
    Err(OpenError::NotBuilt("haply"))
}

/// The first HID force-feedback device, else the first SpaceMouse (as input only).
#[cfg(feature = "hid")]
fn open_hid(path: Option<&str>, specs: &DeviceSpecs) -> Result<Box<dyn Device>, OpenError> {
    use crate::hid::{PidForceDevice, PidReportIds, SpaceMouse, SpaceMouseMode};
    // A missing force-feedback device is the usual case: the SpaceMouse is tried next.
    if let Ok(d) = PidForceDevice::open(PidReportIds::default(), specs.peak_force_n, path) {
        return Ok(Box::new(d));
    }
    let mode = SpaceMouseMode::Rate { metres_per_s_per_count: 2e-4, radians_per_s_per_count: 2e-3 };
    let device = SpaceMouse::open(mode, path).map_err(|e| OpenError::Hid(e.to_string()))?;
    Ok(Box::new(device))
}

#[cfg(not(feature = "hid"))]
fn open_hid(_: Option<&str>, _: &DeviceSpecs) -> Result<Box<dyn Device>, OpenError> {
    Err(OpenError::NotBuilt("hid"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn device_names_parse_and_bad_ones_say_what_is_accepted() {
        assert_eq!("sim".parse(), Ok(DeviceChoice::Sim));
        assert_eq!("trace:/tmp/a.csv".parse(), Ok(DeviceChoice::Trace("/tmp/a.csv".into())));
        assert_eq!("hid".parse(), Ok(DeviceChoice::Hid(None)));
        assert_eq!("hid:/dev/hidraw2".parse(), Ok(DeviceChoice::Hid(Some("/dev/hidraw2".into()))));
        assert_eq!("falcon".parse(), Ok(DeviceChoice::Falcon(None)));
        assert_eq!(
            "falcon:/opt/novint/nvent_firmware.bin".parse(),
            Ok(DeviceChoice::Falcon(Some("/opt/novint/nvent_firmware.bin".into())))
        );
        assert_eq!("haply".parse(), Ok(DeviceChoice::Haply("ws://localhost:10001/".into())));
        assert_eq!("haply:ws://10.0.0.2:10001/".parse(), Ok(DeviceChoice::Haply("ws://10.0.0.2:10001/".into())));
        let err = "trace:".parse::<DeviceChoice>().unwrap_err();
        assert!(err.contains("sim, trace:FILE, hid[:PATH], falcon[:FIRMWARE] or haply[:URL]"), "{err}");
        assert!("inverse3".parse::<DeviceChoice>().is_err());
    }

    #[test]
    fn a_trace_that_is_not_there_is_refused_naming_the_file() {
        let choice = DeviceChoice::Trace("/nonexistent/hand.csv".into());
        let Err(e) = open(&choice, crate::presets::touch(), Vec3::ZERO) else { panic!("opened a missing trace") };
        let e = e.to_string();
        assert!(e.starts_with("the trace /nonexistent/hand.csv: reading it:") && !e.contains('\n'), "{e}");
    }

    #[test]
    fn a_simulated_device_comes_with_its_hand_and_no_link() {
        let opened = open(&DeviceChoice::Sim, crate::presets::touch(), Vec3::Y * 0.05).expect("a sim opens");
        assert!(opened.hand.is_some() && matches!(opened.link, DeviceLink::Local));
        assert_eq!(opened.device.specs().name, "3D Systems Touch");
    }
}
