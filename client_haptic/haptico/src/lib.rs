#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

#[cfg(test)]
#[global_allocator]
static ALLOCATOR: assert_no_alloc::AllocDisabler = assert_no_alloc::AllocDisabler;

pub mod choice;
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
pub mod steer;
pub mod thread;
pub mod timing;
pub mod trace;

pub use crate::core::{HapticCore, HapticEvents};
pub use choice::{DeviceChoice, DeviceLink, OpenError};
pub use device::{Device, DeviceSpecs};
pub use error::{HapticoError, Result};
pub use mock::{MockDevice, MockLog};
pub use thread::{CommandQueueFull, HapticConfig, HapticHandle, HapticTelemetry};
pub use timing::{HapticClock, TickTiming, TimingSummary};
