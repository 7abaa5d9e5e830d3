//! The Falcon's USB link: an FTDI serial bridge (0403:cb48), driven from user space through `nusb`.
//!
//! You need this module to find a Falcon, load its firmware and exchange packets with it. The FTDI
//! requests (purge, modem lines, baud divisor, latency timer) and the firmware-loading handshake follow
//! the libnifalcon project's documentation of the device (facts only). Novint's firmware is not ours to
//! ship: the player names their copy (it comes with Novint's driver). Untested against hardware: with no
//! Falcon plugged in, [`FtdiLink::open_first`] says so at once.

use std::path::Path;
use std::time::Duration;

use nusb::MaybeFuture;
use nusb::transfer::{Buffer, Bulk, ControlOut, ControlType, In, Out, Recipient};

use super::device::{Transport, TransportError};
use super::packet::PACKET_LEN;
use crate::{HapticoError, Result};

/// The Falcon's USB vendor id (FTDI).
pub const VENDOR_ID: u16 = 0x0403;
/// The Falcon's USB product id.
pub const PRODUCT_ID: u16 = 0xCB48;
/// The udev rule that lets a player's programs open the Falcon on Linux.
pub const UDEV_RULE: &str =
    r#"SUBSYSTEM=="usb", ATTR{idVendor}=="0403", ATTR{idProduct}=="cb48", MODE="0660", TAG+="uaccess""#;

const REQUEST_RESET: u8 = 0;
const REQUEST_MODEM: u8 = 1;
const REQUEST_FLOW: u8 = 2;
const REQUEST_BAUD: u8 = 3;
const REQUEST_DATA: u8 = 4;
const REQUEST_LATENCY: u8 = 9;
const PURGE_RX: u16 = 1;
const PURGE_TX: u16 = 2;
const DTR_HIGH: u16 = 0x0101;
const DTR_LOW: u16 = 0x0100;
const RTS_LOW: u16 = 0x0200;
const BAUD_9600: u16 = 0x4138;
const BAUD_140000: u16 = 0x0015;
const BAUD_NORMAL: u16 = 0x0002;
const DATA_8N1: u16 = 8;
/// Bytes of modem status FTDI puts at the start of every USB packet it sends.
const STATUS_BYTES: usize = 2;
const USB_PACKET: usize = 64;
const CONTROL_TIMEOUT: Duration = Duration::from_millis(100);

/// An open FTDI link to a Falcon.
pub struct FtdiLink {
    interface: nusb::Interface,
    out: nusb::Endpoint<Bulk, Out>,
    input: nusb::Endpoint<Bulk, In>,
    out_buffer: Option<Buffer>,
    in_buffer: Option<Buffer>,
    /// Data received but not yet taken (status bytes removed).
    pending: [u8; USB_PACKET],
    pending_len: usize,
    timeout: Duration,
}

fn usb_error(what: &str, e: impl std::fmt::Display) -> HapticoError {
    HapticoError::Usb(format!("{what}: {e}"))
}

/// How many Falcons are plugged in (without opening them), or why USB could not be listed.
pub fn count_plugged_in() -> std::result::Result<usize, String> {
    let devices = nusb::list_devices().wait().map_err(|e| e.to_string())?;
    Ok(devices.filter(|d| d.vendor_id() == VENDOR_ID && d.product_id() == PRODUCT_ID).count())
}

impl FtdiLink {
    /// Opens the first Falcon plugged in. No Falcon: [`HapticoError::NoDevice`] with what to check.
    pub fn open_first() -> Result<Self> {
        let no_falcon =
            |why: String| HapticoError::NoDevice { wanted: "Novint Falcon (USB 0403:cb48)".into(), hint: why };
        let found = nusb::list_devices()
            .wait()
            .map_err(|e| no_falcon(format!("USB devices could not be listed ({e})")))?
            .find(|d| d.vendor_id() == VENDOR_ID && d.product_id() == PRODUCT_ID);
        let Some(info) = found else {
            return Err(no_falcon(
                "check that it is plugged in and powered (its own power supply, not only USB)".into(),
            ));
        };
        let device = info.open().wait().map_err(|e| {
            usb_error(&format!("opening the Falcon (permission? install the udev rule {UDEV_RULE})"), e)
        })?;
        let interface =
            device.detach_and_claim_interface(0).wait().map_err(|e| usb_error("claiming the Falcon's interface", e))?;
        let out = interface.endpoint::<Bulk, Out>(0x02).map_err(|e| usb_error("the Falcon's OUT endpoint", e))?;
        let input = interface.endpoint::<Bulk, In>(0x81).map_err(|e| usb_error("the Falcon's IN endpoint", e))?;
        let (out_buffer, in_buffer) = (Some(out.allocate(USB_PACKET)), Some(input.allocate(USB_PACKET)));
        Ok(Self {
            interface,
            out,
            input,
            out_buffer,
            in_buffer,
            pending: [0; USB_PACKET],
            pending_len: 0,
            timeout: Duration::from_millis(100),
        })
    }

    fn control(&self, request: u8, value: u16) -> Result<()> {
        let data = ControlOut {
            control_type: ControlType::Vendor,
            recipient: Recipient::Device,
            request,
            value,
            index: 0,
            data: &[],
        };
        self.interface.control_out(data, CONTROL_TIMEOUT).wait().map_err(|e| usb_error("an FTDI request", e))
    }

    fn purge(&mut self) -> Result<()> {
        self.pending_len = 0;
        self.control(REQUEST_RESET, PURGE_RX)?;
        self.control(REQUEST_RESET, PURGE_TX)
    }

    fn write(&mut self, bytes: &[u8]) -> std::result::Result<(), TransportError> {
        let mut buffer = self.out_buffer.take().unwrap_or_else(|| self.out.allocate(USB_PACKET));
        buffer.clear();
        buffer.extend_from_slice(bytes);
        let done = self.out.transfer_blocking(buffer, self.timeout);
        let ok = done.status.is_ok() && done.actual_len == bytes.len();
        let failed = done.status.err();
        self.out_buffer = Some(done.buffer);
        match failed {
            Some(nusb::transfer::TransferError::Disconnected) => Err(TransportError::Disconnected),
            _ if ok => Ok(()),
            _ => Err(TransportError::Timeout),
        }
    }

    /// Fills `into` from the link, removing FTDI's status bytes from each USB packet.
    fn read(&mut self, into: &mut [u8]) -> std::result::Result<(), TransportError> {
        let mut filled = 0;
        for _ in 0..16 {
            let take = self.pending_len.min(into.len() - filled);
            into[filled..filled + take].copy_from_slice(&self.pending[..take]);
            self.pending.copy_within(take..self.pending_len, 0);
            self.pending_len -= take;
            filled += take;
            if filled == into.len() {
                return Ok(());
            }
            let mut buffer = self.in_buffer.take().unwrap_or_else(|| self.input.allocate(USB_PACKET));
            buffer.set_requested_len(USB_PACKET);
            let done = self.input.transfer_blocking(buffer, self.timeout);
            let status = done.status;
            let data = done.buffer;
            if status.is_ok() && data.len() > STATUS_BYTES {
                let payload = &data[STATUS_BYTES..];
                self.pending[..payload.len()].copy_from_slice(payload);
                self.pending_len = payload.len();
            }
            self.in_buffer = Some(data);
            if let Err(nusb::transfer::TransferError::Disconnected) = status {
                return Err(TransportError::Disconnected);
            }
        }
        Err(TransportError::Timeout)
    }

    /// Loads Novint's firmware image from `path` into the Falcon (its handshake at 9600 baud, the
    /// upload at 140,000 with every byte echoed back and compared), then switches to normal mode.
    pub fn load_firmware(&mut self, path: &Path) -> Result<()> {
        let image = std::fs::read(path).map_err(|source| HapticoError::Io { path: path.to_owned(), source })?;
        let failed =
            |what: &str| HapticoError::Usb(format!("loading the Falcon's firmware from {}: {what}", path.display()));
        self.purge()?;
        self.control(REQUEST_LATENCY, 16)?;
        self.control(REQUEST_BAUD, BAUD_9600)?;
        self.control(REQUEST_DATA, DATA_8N1)?;
        self.control(REQUEST_FLOW, 0)?;
        self.control(REQUEST_MODEM, RTS_LOW)?;
        self.control(REQUEST_MODEM, DTR_LOW)?;
        self.control(REQUEST_MODEM, DTR_HIGH)?;
        let mut answer = [0u8; 4];
        let mut ready = false;
        for _ in 0..100 {
            if self.write(&[0x0A, 0x43, 0x0D]).is_ok()
                && self.read(&mut answer).is_ok()
                && answer == [0x0A, 0x44, 0x2C, 0x0D]
            {
                ready = true;
                break;
            }
        }
        if !ready {
            return Err(failed("it did not answer the loader's handshake"));
        }
        self.control(REQUEST_MODEM, DTR_LOW)?;
        self.control(REQUEST_BAUD, BAUD_140000)?;
        let mut echo = [0u8; 1];
        if self.write(&[0x41]).is_err() || self.read(&mut echo).is_err() || echo[0] != 0x41 {
            return Err(failed("it did not echo the start of the upload"));
        }
        let mut back = [0u8; 62];
        for chunk in image.chunks(62) {
            let back = &mut back[..chunk.len()];
            if self.write(chunk).is_err() || self.read(back).is_err() || back != chunk {
                return Err(failed("a chunk did not come back as sent"));
            }
        }
        self.normal_mode()
    }

    /// Switches the link to the running firmware's settings (1 ms latency, its baud divisor).
    pub fn normal_mode(&mut self) -> Result<()> {
        self.control(REQUEST_LATENCY, 1)?;
        self.control(REQUEST_BAUD, BAUD_NORMAL)?;
        self.purge()?;
        self.timeout = Duration::from_millis(5);
        Ok(())
    }
}

impl Transport for FtdiLink {
    fn exchange(
        &mut self,
        out: &[u8; PACKET_LEN],
        reply: &mut [u8; PACKET_LEN],
    ) -> std::result::Result<(), TransportError> {
        self.write(out)?;
        self.read(reply)
    }
}
