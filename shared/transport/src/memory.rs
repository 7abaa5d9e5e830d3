//! An in-memory network of one [`ServerIntake`] and any number of [`ClientIntake`]s, for tests and the
//! fuzz target (feature `test-support`): the same code paths as the game's sockets, without sockets.

use std::net::SocketAddr;
use std::time::Duration;

use renet::{ConnectionConfig, RenetClient, RenetServer};
use renetcode::{ClientAuthentication, ConnectToken, ServerAuthentication, ServerConfig};

use crate::{ClientIntake, IntakeLimits, Refused, ServerIntake};

/// Protocol id of the in-memory network.
pub const PROTOCOL_ID: u64 = 0x4D45_4D4E_4554;
/// The server's address.
pub const SERVER_ADDR: SocketAddr =
    SocketAddr::V4(std::net::SocketAddrV4::new(std::net::Ipv4Addr::new(10, 0, 0, 1), 5000));
/// Wall-clock time the network starts at (netcode checks token expiry against it).
pub const START: Duration = Duration::from_secs(1_800_000_000);
/// One frame.
pub const FRAME: Duration = Duration::from_millis(16);

/// A server and the datagrams it sent, by destination.
pub struct MemoryServer {
    /// The intake under test.
    pub intake: ServerIntake,
    /// renet behind it.
    pub renet: RenetServer,
    /// Datagrams the server sent, not yet delivered.
    pub sent: Vec<(SocketAddr, Vec<u8>)>,
    key: [u8; 32],
    config: ConnectionConfig,
}

impl MemoryServer {
    /// A secure server with renet's default channels and the default limits.
    pub fn new() -> Self {
        Self::with(ConnectionConfig::default(), IntakeLimits::default())
    }

    /// A secure server with these channels and limits.
    pub fn with(config: ConnectionConfig, limits: IntakeLimits) -> Self {
        let key = [0x42; 32];
        let server_config = ServerConfig {
            current_time: START,
            max_clients: 8,
            protocol_id: PROTOCOL_ID,
            public_addresses: vec![SERVER_ADDR],
            authentication: ServerAuthentication::Secure { private_key: key },
        };
        Self {
            intake: ServerIntake::new(server_config, limits),
            renet: RenetServer::new(config.clone()),
            sent: Vec::new(),
            key,
            config,
        }
    }

    /// A connect token for `client_id`.
    pub fn token(&self, client_id: u64) -> ConnectToken {
        ConnectToken::generate(START, PROTOCOL_ID, 300, client_id, 15, vec![SERVER_ADDR], None, &self.key)
            .unwrap_or_else(|e| unreachable!("a token with one address always encodes: {e}"))
    }

    /// Hands one datagram from `from` to the intake.
    pub fn deliver(&mut self, from: SocketAddr, datagram: &[u8]) -> Result<(), Refused> {
        let mut buf = datagram.to_vec();
        let sent = &mut self.sent;
        self.intake.receive(from, &mut buf, &mut self.renet, &mut |to, bytes| sent.push((to, bytes.to_vec())))
    }

    /// One server frame after receiving: renet's clock, keep-alives, timeouts, renet's packets.
    pub fn frame(&mut self) {
        let sent = &mut self.sent;
        let mut send = |to, bytes: &[u8]| sent.push((to, bytes.to_vec()));
        self.intake.advance(FRAME);
        self.renet.update(FRAME);
        self.intake.update(&mut self.renet, &mut send);
        self.intake.send_packets(&mut self.renet, &mut send);
    }

    /// A client at `addr` holding a token for `client_id`, using this server's channels.
    pub fn client(&self, addr: SocketAddr, client_id: u64) -> MemoryClient {
        MemoryClient::new(addr, self.token(client_id), self.config.clone())
    }
}

impl Default for MemoryServer {
    fn default() -> Self {
        Self::new()
    }
}

/// A client and the datagrams it sent.
pub struct MemoryClient {
    /// Its address.
    pub addr: SocketAddr,
    /// The intake under test.
    pub intake: ClientIntake,
    /// renet behind it.
    pub renet: RenetClient,
    /// Datagrams sent to the server, not yet delivered.
    pub sent: Vec<Vec<u8>>,
}

impl MemoryClient {
    /// A client connecting with `token`.
    pub fn new(addr: SocketAddr, token: ConnectToken, config: ConnectionConfig) -> Self {
        let intake = ClientIntake::new(START, ClientAuthentication::Secure { connect_token: token })
            .unwrap_or_else(|e| unreachable!("a secure client always starts: {e}"));
        Self { addr, intake, renet: RenetClient::new(config), sent: Vec::new() }
    }

    /// One client frame: receives `inbox`, then sends.
    pub fn frame(&mut self, inbox: Vec<Vec<u8>>) {
        let sent = &mut self.sent;
        let mut send = |_to, bytes: &[u8]| sent.push(bytes.to_vec());
        let _ = self.intake.begin_update(&mut self.renet, &mut send);
        for mut datagram in inbox {
            let _ = self.intake.receive(SERVER_ADDR, &mut datagram, &mut self.renet);
        }
        self.renet.update(FRAME);
        self.intake.finish_update(FRAME, &mut send);
        let _ = self.intake.send_packets(&mut self.renet, &mut send);
    }
}

/// Runs `frames` frames of the server and `clients`, delivering every datagram the next frame.
pub fn run(server: &mut MemoryServer, clients: &mut [&mut MemoryClient], frames: usize) {
    for _ in 0..frames {
        for c in clients.iter_mut() {
            for datagram in std::mem::take(&mut c.sent) {
                let _ = server.deliver(c.addr, &datagram);
            }
        }
        server.frame();
        let mut sent = std::mem::take(&mut server.sent);
        for c in clients.iter_mut() {
            let (mine, rest): (Vec<_>, Vec<_>) = sent.into_iter().partition(|(to, _)| *to == c.addr);
            sent = rest;
            c.frame(mine.into_iter().map(|(_, d)| d).collect());
        }
    }
}

/// A netcode client with no checks and no renet: what an attacker holding a token controls.
pub struct RawClient {
    /// Its address.
    pub addr: SocketAddr,
    /// Its netcode state.
    pub netcode: renetcode::NetcodeClient,
}

impl RawClient {
    /// A client that sent its connection request and got the challenge: the server holds it pending.
    pub fn pending(server: &mut MemoryServer, addr: SocketAddr, client_id: u64) -> Self {
        let token = server.token(client_id);
        let netcode = renetcode::NetcodeClient::new(START, ClientAuthentication::Secure { connect_token: token })
            .unwrap_or_else(|e| unreachable!("a secure client always starts: {e}"));
        let mut client = Self { addr, netcode };
        client.step(server, Duration::ZERO);
        client
    }

    /// A client through the whole handshake: the server holds it connected.
    pub fn connected(server: &mut MemoryServer, addr: SocketAddr, client_id: u64) -> Self {
        let mut client = Self::pending(server, addr, client_id);
        for _ in 0..8 {
            if client.netcode.is_connected() {
                break;
            }
            client.step(server, FRAME);
        }
        client
    }

    /// Sends netcode's next handshake packet and reads the server's answers to it.
    fn step(&mut self, server: &mut MemoryServer, dt: Duration) {
        if let Some((packet, _)) = self.netcode.update(dt) {
            let packet = packet.to_vec();
            let _ = server.deliver(self.addr, &packet);
        }
        let (mine, rest): (Vec<_>, Vec<_>) =
            std::mem::take(&mut server.sent).into_iter().partition(|(to, _)| *to == self.addr);
        server.sent = rest;
        for (_, mut datagram) in mine {
            let _ = self.netcode.process_packet(&mut datagram);
        }
    }

    /// `packet` as a payload datagram (a bundle of that packet alone) sealed with this client's key
    /// (empty when not connected).
    pub fn seal(&mut self, packet: &[u8]) -> Vec<u8> {
        self.seal_bundle(&crate::bundle::single(packet))
    }

    /// `bundle` as it is, sealed with this client's key: a payload that need not be a well-formed bundle
    /// (empty when not connected).
    pub fn seal_bundle(&mut self, bundle: &[u8]) -> Vec<u8> {
        self.netcode.generate_payload_packet(bundle).map(|(_, bytes)| bytes.to_vec()).unwrap_or_default()
    }
}

/// The crafted packets each of the guarded upstream bugs panics on, for tests and fuzz seeds.
pub mod crafted {
    /// A netcode response announcing a 15-byte sequence (renetcode 2.0.0, `packet.rs:375`).
    pub fn crashing_prefix() -> Vec<u8> {
        let mut d = vec![0xF3];
        d.extend_from_slice(&[0xAB; 17]);
        d
    }

    /// A keep-alive announcing an 8-byte sequence with 9 bytes left for a 16-byte tag (`crypto.rs:10`).
    pub fn short_with_long_sequence() -> Vec<u8> {
        let mut d = vec![0x84];
        d.extend_from_slice(&[0xCD; 17]);
        d
    }

    /// A keep-alive with sequence `u64::MAX` (replay window overflow, `replay_protection.rs:25`).
    pub fn huge_sequence() -> Vec<u8> {
        let mut d = vec![0x84];
        d.extend_from_slice(&[0xFF; 8]);
        d.extend_from_slice(&[0u8; 16]);
        d
    }

    /// A reliable renet slice on `channel` with a full 1200-byte payload (renet checks the size of a
    /// slice that is not the last before it indexes, so only a full one reaches `slice_constructor.rs:41`).
    pub fn renet_slice(channel: u8, message_id: u8, index: u8, count: u8) -> Vec<u8> {
        // Type 2 (reliable slice), sequence 1, then one-byte varints (< 64) and 0x44B0 = varint 1200.
        assert!(message_id < 64 && index < 64 && count < 64, "one-byte varints only");
        let mut p = vec![2, 1, channel, message_id, index, count, 0x44, 0xB0];
        p.extend_from_slice(&[0x5A; 1200]);
        p
    }
}
