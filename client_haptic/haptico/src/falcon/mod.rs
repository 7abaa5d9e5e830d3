//! The Novint Falcon at its protocol boundary: the firmware's packets ([`packet`]), the delta
//! mechanism's kinematics ([`kinematics`]), homing ([`homing`]) and the [`Device`](crate::Device) on a
//! packet [`Transport`](device::Transport) ([`device`]).
//!
//! You need this module to drive a Falcon. Groundwork only: the USB transport (FTDI, firmware upload)
//! is not built yet, so no program drives a real Falcon and `--device falcon` is not accepted
//! (issue 19); the device is tested against a simulated firmware.

pub mod device;
pub mod homing;
pub mod kinematics;
pub mod packet;
