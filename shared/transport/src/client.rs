//! The client's side of the UDP transport: only datagrams from the server's address with a header netcode
//! can parse reach netcode, and every renet packet of a decrypted payload (a bundle: [`crate::bundle`])
//! passes a [`SliceGuard`] before renet.
//!
//! Like [`crate::server::ServerIntake`], [`ClientIntake`] owns no socket.

use std::net::SocketAddr;
use std::time::Duration;

use renet::RenetClient;
use renetcode::{ClientAuthentication, DisconnectReason, NetcodeClient, NetcodeError};

use crate::bundle::Bundler;
use crate::datagram::DatagramRefusal;
use crate::datagram::{Direction, check_datagram};
use crate::error::TransportError;
use crate::payload::SliceGuard;
use crate::server::{Refused, Send};

/// Largest server message a client accepts, in slices of 1200 bytes (4.9 MB: renet's channel memory).
pub const CLIENT_MAX_SLICES: u64 = 4096;

/// Checks and forwards every datagram of a client's socket.
#[derive(Debug)]
pub struct ClientIntake {
    netcode: NetcodeClient,
    slices: SliceGuard,
    refused: u64,
    bundler: Bundler,
}

impl ClientIntake {
    /// A client connecting with `authentication`, at time `now` (since the Unix epoch).
    pub fn new(now: Duration, authentication: ClientAuthentication) -> Result<Self, NetcodeError> {
        Ok(Self {
            netcode: NetcodeClient::new(now, authentication)?,
            slices: SliceGuard::new(CLIENT_MAX_SLICES),
            refused: 0,
            bundler: Bundler::new(),
        })
    }

    /// The server's address.
    pub fn server_addr(&self) -> SocketAddr {
        self.netcode.server_addr()
    }

    /// The netcode client id.
    pub fn client_id(&self) -> u64 {
        self.netcode.client_id()
    }

    /// Why netcode gave up, if it did.
    pub fn disconnect_reason(&self) -> Option<DisconnectReason> {
        self.netcode.disconnect_reason()
    }

    /// Datagrams and payloads refused so far.
    pub fn refused(&self) -> u64 {
        self.refused
    }

    /// Starts a frame: mirrors netcode's state into renet, or reports why the connection is over (after
    /// telling the server, when renet gave up).
    pub fn begin_update(&mut self, renet: &mut RenetClient, send: &mut Send<'_>) -> Result<(), TransportError> {
        if let Some(reason) = self.netcode.disconnect_reason() {
            renet.disconnect_due_to_transport();
            return Err(TransportError::Netcode(NetcodeError::Disconnected(reason)));
        }
        if let Some(reason) = renet.disconnect_reason() {
            let (addr, packet) = self.netcode.disconnect()?;
            send(addr, packet);
            return Err(TransportError::Renet(reason));
        }
        if self.netcode.is_connected() {
            renet.set_connected();
        } else if self.netcode.is_connecting() {
            renet.set_connecting();
        }
        Ok(())
    }

    /// Takes one datagram from `from`.
    pub fn receive(&mut self, from: SocketAddr, datagram: &mut [u8], renet: &mut RenetClient) -> Result<(), Refused> {
        let checked = if from != self.netcode.server_addr() {
            Err(DatagramRefusal::NotFromServer)
        } else {
            check_datagram(datagram, Direction::ToClient).map(|_| ())
        };
        if let Err(r) = checked {
            self.refused += 1;
            return Err(Refused::Datagram(r));
        }
        let Some(payload) = self.netcode.process_packet(datagram) else { return Ok(()) };
        let delivered = crate::bundle::unbundle(payload).and_then(|packets| {
            for packet in packets {
                self.slices.check(packet)?;
                renet.process_packet(packet);
            }
            Ok(())
        });
        delivered.map_err(|r| {
            self.refused += 1;
            Refused::Payload(r)
        })
    }

    /// Ends a frame: advances netcode by `dt` and sends its keep-alive or handshake packet.
    pub fn finish_update(&mut self, dt: Duration, send: &mut Send<'_>) {
        if let Some((packet, addr)) = self.netcode.update(dt) {
            send(addr, packet);
        }
    }

    /// Sends renet's packets, bundled: one datagram for all that fit.
    pub fn send_packets(&mut self, renet: &mut RenetClient, send: &mut Send<'_>) -> Result<(), TransportError> {
        if let Some(reason) = self.netcode.disconnect_reason() {
            return Err(TransportError::Netcode(NetcodeError::Disconnected(reason)));
        }
        let Self { netcode, bundler, .. } = self;
        bundler.pack(renet.get_packets_to_send(), |bundle| {
            let (addr, bytes) = netcode.generate_payload_packet(bundle)?;
            send(addr, bytes);
            Ok::<_, TransportError>(())
        })
    }

    /// Tells the server we leave.
    pub fn disconnect(&mut self, send: &mut Send<'_>) {
        if self.netcode.is_disconnected() {
            return;
        }
        if let Ok((addr, packet)) = self.netcode.disconnect() {
            send(addr, packet);
        }
    }
}
