//! The Novint Falcon at its protocol boundary: the firmware's packets ([`packet`]), the delta
//! mechanism's kinematics ([`kinematics`]), homing ([`homing`]) and the [`Device`](crate::Device) on a
//! packet [`Transport`](device::Transport) ([`device`]).
//!
//! You need this module to drive a Falcon: [`open`] finds it on USB ([`usb`]), loads Novint's firmware
//! when it is not running yet, and runs it on an I/O thread ([`crate::io::IoDevice`]). Tested at the
//! protocol boundary (a simulated firmware) and for the no-Falcon case only: never against hardware.

pub mod device;
pub mod homing;
pub mod kinematics;
pub mod packet;
#[cfg(feature = "falcon")]
pub mod usb;

#[cfg(feature = "falcon")]
pub use open_falcon::open;

#[cfg(feature = "falcon")]
mod open_falcon {
    use std::path::Path;
    use std::sync::Arc;

    use super::device::{FalconDevice, FalconStatus};
    use super::usb::FtdiLink;
    use crate::io::IoDevice;
    use crate::{Device, HapticoError, Result};

    /// Exchanges tried to see whether the firmware answers.
    const PROBES: u64 = 20;

    /// Opens the first Falcon, loads the firmware at `firmware` if it is not running yet, and starts its
    /// I/O thread (1 kHz). Fails at once with no Falcon plugged in, and with what to do when the firmware
    /// is needed but not given.
    pub fn open(firmware: Option<&Path>) -> Result<(IoDevice, Arc<FalconStatus>)> {
        let mut link = FtdiLink::open_first()?;
        link.normal_mode()?;
        let mut falcon = FalconDevice::new(link, crate::presets::falcon());
        let status = falcon.status();
        let answers = |falcon: &mut FalconDevice<FtdiLink>| {
            (0..PROBES).any(|t| {
                falcon.read_state(t * 1000);
                status.replies() > 0
            })
        };
        if !answers(&mut falcon) {
            let Some(path) = firmware else {
                return Err(HapticoError::NoDevice {
                    wanted: "running Falcon firmware".into(),
                    hint: "the Falcon needs Novint's firmware loaded: give its file, --device falcon:PATH \
                           (nvent_firmware.bin from Novint's driver; it cannot be shipped with this game)"
                        .into(),
                });
            };
            falcon.transport_mut().load_firmware(path)?;
            if !answers(&mut falcon) {
                return Err(HapticoError::Usb(format!(
                    "the firmware from {} was loaded but the Falcon does not answer",
                    path.display()
                )));
            }
        }
        Ok((IoDevice::spawn(falcon, 1000.0, "falcon-io")?, status))
    }
}
