//! haptico: the haptic device layer (paper §3.3).
//!
//! A [`Device`] trait with simulated ([`sim`]), recorded ([`trace`]), mock ([`mock`]), HID (`hid`), Novint
//! Falcon ([`falcon`]) and Haply Inverse3 (`haply`) backends, an I/O thread for devices whose I/O blocks ([`io`]), and the 1 kHz haptic thread ([`thread`]) that reads the device, broadcasts `OnTransform`,
//! gathers forces through `ForceOnHapticTick` and commands the device. It depends only on
//! `haptic_common`; force computation and collision detection plug in through the events.
//!
//! ```no_run
//! use haptico::{HapticClock, HapticConfig, HapticEvents, HapticHandle, presets};
//! use haptico::sim::{SimConfig, SimDevice, TargetPath};
//! use haptic_common::{ForceOnHapticTick, ForceTorque, Pose};
//!
//! let device = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::Hold(Pose::IDENTITY));
//! let mut events = HapticEvents::default();
//! events.force_on_haptic_tick.add_delegate(|tick: &ForceOnHapticTick| {
//!     // A soft floor at y = 0: 300 N/m.
//!     let y = tick.device.pose.translation.y;
//!     if y < 0.0 {
//!         tick.add(ForceTorque { force: glam::Vec3::Y * (-300.0 * y), torque: glam::Vec3::ZERO });
//!     }
//! });
//! let handle = HapticHandle::spawn(device, events, HapticConfig::default(), HapticClock::new())?;
//! std::thread::sleep(std::time::Duration::from_millis(100));
//! println!("{:?}", handle.telemetry());
//! handle.stop();
//! # Ok::<(), haptico::HapticoError>(())
//! ```
#![warn(missing_docs)]

#[cfg(test)]
#[global_allocator]
static ALLOCATOR: assert_no_alloc::AllocDisabler = assert_no_alloc::AllocDisabler;

pub mod core;
pub mod device;
pub mod error;
pub mod falcon;
#[cfg(feature = "haply")]
pub mod haply;
#[cfg(feature = "hid")]
pub mod hid;
pub mod io;
pub mod mock;
pub mod presets;
pub mod sim;
pub mod thread;
pub mod timing;
pub mod trace;

pub use crate::core::{HapticCore, HapticEvents};
pub use device::{Device, DeviceSpecs};
pub use error::{HapticoError, Result};
pub use mock::{MockDevice, MockLog};
pub use thread::{CommandQueueFull, HapticConfig, HapticHandle, HapticTelemetry};
pub use timing::{HapticClock, TickTiming, TimingSummary};
