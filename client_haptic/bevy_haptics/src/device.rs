//! Which device the haptic thread drives, where its workspace sits in the world, and the simulated
//! hand a game (or a test) steers when there is no real device.
//!
//! You need this module to choose the device: insert a [`HapticDevice`] before the app starts (default:
//! a simulated Phantom Desktop), by name (`sim`, `trace:FILE`, `hid[:PATH]`, `falcon[:FIRMWARE]`,
//! `haply[:URL]`: haptico's [`DeviceChoice`]) or as any [`Device`] you opened yourself.

use std::path::PathBuf;
use std::sync::Mutex;

use bevy::prelude::*;
use haptic_common::Pose;
use haptico::steer::{HandControl, HandGoal};
use haptico::{Device, DeviceChoice, DeviceLink, DeviceSpecs, HapticClock};

/// The device, chosen before the app starts.
#[derive(Resource, Debug)]
pub struct HapticDevice {
    /// What device.
    pub kind: DeviceKind,
    /// Where the device's origin sits in the world (translation and rotation; scale ignored), and how
    /// many world metres a device metre is (`scale`).
    pub origin: Transform,
    /// World metres per device metre (default 1).
    pub scale: f32,
    /// Haptic thread rate, Hz (default 1000).
    pub rate_hz: f32,
    /// Real-time FIFO priority for the haptic thread (the collision thread gets one less), 1..=99
    /// (default none: needs the right to use it).
    pub realtime_priority: Option<i32>,
    /// Record every tick (the device's state and the force sent) to this trace file, to replay later
    /// with `HapticDevice::named("trace:FILE")` (default none). A file that cannot be written leaves
    /// [`HapticStatus::Failed`](crate::HapticStatus::Failed) saying why.
    pub record: Option<PathBuf>,
}

impl Default for HapticDevice {
    fn default() -> Self {
        Self {
            kind: DeviceKind::default(),
            origin: Transform::IDENTITY,
            scale: 1.0,
            rate_hz: 1000.0,
            realtime_priority: None,
            record: None,
        }
    }
}

impl HapticDevice {
    /// A simulated device copying the preset named `preset` (see [`DeviceKind::Named`]), its hand
    /// resting at `start` (device frame, m).
    pub fn simulated(preset: &str, start: Vec3) -> Self {
        let kind = DeviceKind::Named { choice: DeviceChoice::Sim, preset: preset.to_owned(), start };
        Self { kind, ..Self::default() }
    }

    /// The device named `name` (`sim`, `trace:FILE`, `hid[:PATH]`, `falcon[:FIRMWARE]`, `haply[:URL]`),
    /// with the Phantom Desktop's limits where the device brings none (sim, trace, HID). A name that is
    /// not a device is refused with the names that are.
    pub fn named(name: &str) -> Result<Self, String> {
        let choice = name.parse()?;
        let (_, preset, start) = DeviceKind::default_named();
        Ok(Self { kind: DeviceKind::Named { choice, preset, start }, ..Self::default() })
    }

    /// Any device opened with haptico (a Falcon, an Inverse3, a HID device, your own [`Device`]).
    pub fn custom(device: Box<dyn Device>) -> Self {
        Self::opened(haptico::choice::Opened { device, hand: None, link: DeviceLink::Local })
    }

    /// A device you opened with [`haptico::choice::open`] (to know its limits before the app starts, or
    /// to report a device that cannot be opened your own way), with its simulated hand (which becomes
    /// the [`SimulatedHand`]) and its link (which becomes the [`HapticDeviceLink`]).
    pub fn opened(opened: haptico::choice::Opened) -> Self {
        Self { kind: DeviceKind::Opened(Mutex::new(Some(opened))), ..Self::default() }
    }

    /// The device frame to world map the rig uses.
    pub(crate) fn map(&self) -> haptic_rig::WorkspaceMap {
        haptic_rig::WorkspaceMap { origin: Pose::new(self.origin.translation, self.origin.rotation), scale: self.scale }
    }
}

/// The kinds of device.
pub enum DeviceKind {
    /// A device by name, opened by haptico.
    Named {
        /// Which device: a simulated one (steered through [`SimulatedHand`]), a trace, a HID device, a
        /// Falcon, an Inverse3.
        choice: DeviceChoice,
        /// The limits of a simulated, replayed or HID device: a haptico preset, by part of its name, any
        /// case: `phantom desktop`, `touch`, `falcon`, `inverse3`, `premium` (6-DOF force and torque), ...
        /// (default the Phantom Desktop: 7.9 N, 6-DOF sensing, 3-DOF force).
        preset: String,
        /// Where a simulated hand rests, and where an Inverse3 is centred, device frame, m.
        start: Vec3,
    },
    /// A device you opened (taken when the app starts).
    Opened(Mutex<Option<haptico::choice::Opened>>),
}

impl DeviceKind {
    fn default_named() -> (DeviceChoice, String, Vec3) {
        (DeviceChoice::Sim, "phantom desktop".into(), Vec3::ZERO)
    }
}

impl std::fmt::Debug for DeviceKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Named { choice, preset, start } => {
                f.debug_struct("Named").field("choice", choice).field("preset", preset).field("start", start).finish()
            }
            Self::Opened(_) => f.write_str("Opened"),
        }
    }
}

impl Default for DeviceKind {
    fn default() -> Self {
        let (choice, preset, start) = Self::default_named();
        Self::Named { choice, preset, start }
    }
}

/// Why the device could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum DeviceError {
    /// No preset by that name.
    #[error("no device preset named {0:?} (haptico::presets has: {1})")]
    NoPreset(String, String),
    /// haptico could not open it.
    #[error(transparent)]
    Open(#[from] haptico::OpenError),
    /// A device opened beforehand was already taken by an earlier start.
    #[error("the device opened beforehand was already used")]
    Taken,
}

fn preset(name: &str) -> Result<DeviceSpecs, DeviceError> {
    haptico::presets::by_name(name).ok_or_else(|| {
        let names: Vec<_> = haptico::presets::all().iter().map(|s| s.name).collect();
        DeviceError::NoPreset(name.to_owned(), names.join(", "))
    })
}

impl DeviceKind {
    pub(crate) fn open(&self) -> Result<haptico::choice::Opened, DeviceError> {
        match self {
            Self::Named { choice, preset: name, start } => Ok(haptico::choice::open(choice, preset(name)?, *start)?),
            Self::Opened(opened) => opened.lock().unwrap_or_else(|p| p.into_inner()).take().ok_or(DeviceError::Taken),
        }
    }
}

/// A real device's link (USB, a service) and its state, to watch while it runs (present once the
/// device is open): e.g. a Falcon's homing, a service that went away.
#[derive(Resource, Clone, Debug)]
pub struct HapticDeviceLink(pub DeviceLink);

/// The simulated device's hand (present while a simulated device, `sim`, runs): where it
/// wants the stylus, sampled by the haptic thread at every tick (device frame). Keys, a mouse, a bot or
/// a scripted path set it; the forces the device renders push back on it like on a hand.
#[derive(Resource)]
pub struct SimulatedHand {
    control: HandControl,
    clock: HapticClock,
}

impl SimulatedHand {
    pub(crate) fn new(control: HandControl, clock: HapticClock) -> Self {
        Self { control, clock }
    }

    /// Sets where the hand goes from now on (times in a goal are on [`SimulatedHand::now_us`]'s clock).
    pub fn set(&mut self, goal: HandGoal) {
        self.control.set(goal);
    }

    /// Moves the hand in a straight line to `to` (device frame, m) in `seconds`, from where it is going now.
    pub fn move_to(&mut self, to: Vec3, seconds: f32) {
        let now = self.now_us();
        let from = self.control.goal().sample(now).translation;
        self.set(HandGoal::Line { from, to, duration_s: seconds, start_us: now });
    }

    /// The goal last set.
    pub fn goal(&self) -> HandGoal {
        self.control.goal()
    }

    /// The haptic clock, µs.
    pub fn now_us(&self) -> u64 {
        self.clock.now_us()
    }
}
