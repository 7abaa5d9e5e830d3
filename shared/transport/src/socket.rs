//! The two things both transports do with their UDP socket: read what waits, bounded, and send.

use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};

/// Receive buffer size: larger than netcode's 1400 so an oversized datagram is seen as such, not cut.
pub const BUFFER_BYTES: usize = 1500;

/// Hands each waiting datagram to `each`, at most `max` of them (a flood waits in the kernel's buffer,
/// and is dropped there, instead of stalling a frame). `Err` only when the socket itself failed.
pub fn drain(
    socket: &UdpSocket,
    buffer: &mut [u8; BUFFER_BYTES],
    max: usize,
    mut each: impl FnMut(SocketAddr, &mut [u8]),
) -> std::io::Result<()> {
    for _ in 0..max {
        match socket.recv_from(&mut buffer[..]) {
            Ok((len, from)) => each(from, &mut buffer[..len]),
            Err(e) if e.kind() == ErrorKind::WouldBlock => break,
            Err(e) if matches!(e.kind(), ErrorKind::Interrupted | ErrorKind::ConnectionReset) => continue,
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// A send function for the intakes over `socket`; a failed send is logged at debug level (UDP may drop).
pub fn send_to(socket: &UdpSocket) -> impl FnMut(SocketAddr, &[u8]) + '_ {
    move |to, bytes| {
        if let Err(e) = socket.send_to(bytes, to) {
            log::debug!("cannot send {} bytes to {to}: {e}", bytes.len());
        }
    }
}
