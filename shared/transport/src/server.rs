//! The server's side of the UDP transport: every datagram is checked, rate-limited and only then handed to
//! netcode; every decrypted payload is checked before renet sees it.
//!
//! [`ServerIntake`] owns no socket: [`ServerIntake::receive`] takes one datagram and the caller's send
//! function, so tests and the fuzz target drive it in memory exactly as the game's socket loop does.

use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};
use std::time::Duration;

use renet::RenetServer;
use renetcode::{NETCODE_USER_DATA_BYTES, NetcodeServer, ServerConfig, ServerResult};

use crate::datagram::{Direction, PacketKind, check_datagram};
use crate::error::{DatagramRefusal, PayloadRefusal};
use crate::limit::{Bucket, KeyedLimiter, Rate, address_key};
use crate::payload::SliceGuard;
use crate::throttle::RefusalLog;

/// The limits of the server's intake.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntakeLimits {
    /// Connection requests per source address (IPv6: per /64); default 10/s, 10 at once (a client sends 4/s).
    pub requests_per_address: Rate,
    /// Connection requests from all addresses together; default 500/s, 500 at once.
    pub requests_total: Rate,
    /// Authenticated datagrams per connected client; default 1000/s, 1000 at once (a player sends ~120/s).
    pub datagrams_per_client: Rate,
    /// Largest client message in slices of 1200 bytes; default 32 (the largest a client sends is ~5 KB).
    pub max_slices: u64,
    /// Refused payloads a client may send (leaking one a second) before it is disconnected; default 20.
    pub refused_payloads_limit: f64,
    /// Addresses whose request rate is tracked at once; default 4096.
    pub tracked_addresses: usize,
}

impl Default for IntakeLimits {
    fn default() -> Self {
        Self {
            requests_per_address: Rate::new(10.0, 10.0),
            requests_total: Rate::new(500.0, 500.0),
            datagrams_per_client: Rate::new(1000.0, 1000.0),
            max_slices: 32,
            refused_payloads_limit: 20.0,
            tracked_addresses: 4096,
        }
    }
}

/// What the intake turned away.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refused {
    /// A datagram, before netcode.
    Datagram(DatagramRefusal),
    /// A connected client's decrypted payload, before renet.
    Payload(PayloadRefusal),
    /// Passed the checks, but netcode turned it away (bad token, failed authentication, replay...).
    Netcode(PacketKind),
}

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refused::Datagram(r) => write!(f, "{r}"),
            Refused::Payload(r) => write!(f, "payload: {r}"),
            Refused::Netcode(kind) => write!(f, "netcode turned away a {kind:?}"),
        }
    }
}

/// Counts of what passed and what did not.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IntakeStats {
    /// Datagrams received.
    pub datagrams: u64,
    /// Datagrams refused before netcode.
    pub refused_datagrams: u64,
    /// Payloads refused before renet.
    pub refused_payloads: u64,
    /// Connection requests and payloads that passed the checks but that netcode turned away.
    pub refused_by_netcode: u64,
    /// Clients disconnected for sending refused payloads.
    pub expelled: u64,
    /// Bytes received.
    pub bytes_in: u64,
    /// Bytes sent.
    pub bytes_out: u64,
}

/// One connected client as the intake sees it.
#[derive(Debug)]
struct Connection {
    addr: SocketAddr,
    slices: SliceGuard,
    datagrams: Bucket,
    strikes: f64,
    strikes_at_s: f64,
    expelled: bool,
}

/// Checks and forwards every datagram of the game socket.
#[derive(Debug)]
pub struct ServerIntake {
    netcode: NetcodeServer,
    limits: IntakeLimits,
    now_s: f64,
    requests: KeyedLimiter<IpAddr>,
    connections: HashMap<u64, Connection>,
    stats: IntakeStats,
    log: RefusalLog,
}

/// Where the intake sends datagrams: (destination, bytes).
pub type Send<'a> = dyn FnMut(SocketAddr, &[u8]) + 'a;

impl ServerIntake {
    /// An intake around a netcode server made from `config`.
    pub fn new(config: ServerConfig, limits: IntakeLimits) -> Self {
        Self {
            netcode: NetcodeServer::new(config),
            requests: KeyedLimiter::new(limits.requests_per_address, limits.requests_total, limits.tracked_addresses),
            limits,
            now_s: 0.0,
            connections: HashMap::new(),
            stats: IntakeStats::default(),
            log: RefusalLog::new("heist_transport::server", "UDP intake"),
        }
    }

    /// Advances time by `dt` (netcode expires pending clients with it).
    pub fn advance(&mut self, dt: Duration) {
        self.now_s += dt.as_secs_f64();
        self.netcode.update(dt);
        self.log.roll(self.now_s);
    }

    /// Takes one datagram from `from`: checks it, lets netcode process it, passes a payload on to renet.
    pub fn receive(
        &mut self,
        from: SocketAddr,
        datagram: &mut [u8],
        renet: &mut RenetServer,
        send: &mut Send<'_>,
    ) -> Result<(), Refused> {
        self.stats.datagrams += 1;
        self.stats.bytes_in += datagram.len() as u64;
        let refusal = match self.admit(from, datagram) {
            Ok(kind) => {
                let result = self.netcode.process_packet(from, datagram);
                let ignored = matches!(result, ServerResult::None);
                let handled = handle(result, renet, &mut self.connections, &self.limits, self.now_s, send);
                self.stats.bytes_out += handled.bytes_out;
                return match handled.refused {
                    Some((client_id, refusal)) => Err(self.refused_payload(client_id, refusal, renet)),
                    // netcode says why only in its own log (`RUST_LOG=renetcode=debug`); a request or a
                    // payload that led nowhere was turned away: a bad, expired or replayed token, a full
                    // server, a packet that failed authentication.
                    None if ignored && matches!(kind, PacketKind::ConnectionRequest | PacketKind::Payload) => {
                        self.stats.refused_by_netcode += 1;
                        let why = format!("netcode turned away a {kind:?} (see RUST_LOG=renetcode=debug)");
                        self.log.refused(from, &why, self.now_s);
                        Err(Refused::Netcode(kind))
                    }
                    None => Ok(()),
                };
            }
            Err(r) => r,
        };
        self.stats.refused_datagrams += 1;
        self.log.refused(from, &refusal, self.now_s);
        Err(Refused::Datagram(refusal))
    }

    /// Header check and, for a connection request, the request rate.
    fn admit(&mut self, from: SocketAddr, datagram: &[u8]) -> Result<PacketKind, DatagramRefusal> {
        let kind = check_datagram(datagram, Direction::ToServer)?;
        if kind == PacketKind::ConnectionRequest && !self.requests.take(address_key(from.ip()), self.now_s) {
            return Err(DatagramRefusal::RateLimited);
        }
        Ok(kind)
    }

    /// Logs a refused payload and disconnects its client once it has sent too many.
    fn refused_payload(&mut self, client_id: u64, refusal: PayloadRefusal, renet: &mut RenetServer) -> Refused {
        self.stats.refused_payloads += 1;
        let Some(c) = self.connections.get_mut(&client_id) else { return Refused::Payload(refusal) };
        self.log.refused(c.addr, &Refused::Payload(refusal), self.now_s);
        if c.strikes > self.limits.refused_payloads_limit && !c.expelled {
            c.expelled = true;
            self.stats.expelled += 1;
            log::warn!("UDP intake: disconnecting client {client_id} at {}: too many refused payloads", c.addr);
            renet.disconnect(client_id);
        }
        Refused::Payload(refusal)
    }

    /// Keep-alives, timeouts and the disconnections renet asked for; call once per frame after receiving.
    pub fn update(&mut self, renet: &mut RenetServer, send: &mut Send<'_>) {
        for id in self.netcode.clients_id() {
            let result = self.netcode.update_client(id);
            self.stats.bytes_out +=
                handle(result, renet, &mut self.connections, &self.limits, self.now_s, send).bytes_out;
        }
        for id in renet.disconnections_id() {
            let result = self.netcode.disconnect(id);
            self.stats.bytes_out +=
                handle(result, renet, &mut self.connections, &self.limits, self.now_s, send).bytes_out;
        }
    }

    /// Sends renet's packets for every connected client.
    pub fn send_packets(&mut self, renet: &mut RenetServer, send: &mut Send<'_>) {
        for id in renet.clients_id() {
            let Ok(packets) = renet.get_packets_to_send(id) else { continue };
            for packet in packets {
                match self.netcode.generate_payload_packet(id, &packet) {
                    Ok((addr, bytes)) => {
                        self.stats.bytes_out += bytes.len() as u64;
                        send(addr, bytes);
                    }
                    Err(e) => {
                        log::error!("UDP intake: cannot encrypt a packet for client {id}: {e}");
                        break;
                    }
                }
            }
        }
    }

    /// Disconnects every client at once (the server is stopping).
    pub fn disconnect_all(&mut self, renet: &mut RenetServer, send: &mut Send<'_>) {
        for id in self.netcode.clients_id() {
            let result = self.netcode.disconnect(id);
            self.stats.bytes_out +=
                handle(result, renet, &mut self.connections, &self.limits, self.now_s, send).bytes_out;
        }
    }

    /// The user data in a connected client's token.
    pub fn user_data(&self, client_id: u64) -> Option<[u8; NETCODE_USER_DATA_BYTES]> {
        self.netcode.user_data(client_id)
    }

    /// A connected client's address.
    pub fn client_addr(&self, client_id: u64) -> Option<SocketAddr> {
        self.netcode.client_addr(client_id)
    }

    /// Counts so far.
    pub fn stats(&self) -> IntakeStats {
        self.stats
    }
}

impl Connection {
    fn new(addr: SocketAddr, limits: &IntakeLimits, now_s: f64) -> Self {
        Self {
            addr,
            slices: SliceGuard::new(limits.max_slices),
            datagrams: Bucket::full(limits.datagrams_per_client, now_s),
            strikes: 0.0,
            strikes_at_s: now_s,
            expelled: false,
        }
    }

    /// Checks one decrypted payload; a refusal adds a strike (leaking one a second).
    fn check(&mut self, payload: &[u8], limits: &IntakeLimits, now_s: f64) -> Result<(), PayloadRefusal> {
        let result = if self.datagrams.take(limits.datagrams_per_client, now_s) {
            self.slices.check(payload)
        } else {
            Err(PayloadRefusal::RateLimited)
        };
        if result.is_err() {
            self.strikes = (self.strikes - (now_s - self.strikes_at_s)).max(0.0) + 1.0;
            self.strikes_at_s = now_s;
        }
        result
    }
}

/// What acting on one netcode result did.
struct Handled {
    bytes_out: u64,
    refused: Option<(u64, PayloadRefusal)>,
}

impl Handled {
    fn sent(bytes: usize) -> Self {
        Self { bytes_out: bytes as u64, refused: None }
    }
}

/// Acts on one netcode result: sends what it says to send, passes a checked payload to renet.
fn handle(
    result: ServerResult<'_, '_>,
    renet: &mut RenetServer,
    connections: &mut HashMap<u64, Connection>,
    limits: &IntakeLimits,
    now_s: f64,
    send: &mut Send<'_>,
) -> Handled {
    match result {
        ServerResult::None => Handled::sent(0),
        ServerResult::PacketToSend { addr, payload } => {
            send(addr, payload);
            Handled::sent(payload.len())
        }
        ServerResult::Payload { client_id, payload } => {
            let Some(connection) = connections.get_mut(&client_id) else { return Handled::sent(0) };
            match connection.check(payload, limits, now_s) {
                Ok(()) => {
                    // Only fails for an unknown client, which netcode just vouched for.
                    let _ = renet.process_packet_from(payload, client_id);
                    Handled::sent(0)
                }
                Err(r) => Handled { bytes_out: 0, refused: Some((client_id, r)) },
            }
        }
        ServerResult::ClientConnected { client_id, addr, payload, .. } => {
            log::info!("UDP intake: client {client_id} connected from {addr}");
            connections.insert(client_id, Connection::new(addr, limits, now_s));
            renet.add_connection(client_id);
            send(addr, payload);
            Handled::sent(payload.len())
        }
        ServerResult::ClientDisconnected { client_id, addr, payload } => {
            log::info!("UDP intake: client {client_id} at {addr} disconnected");
            connections.remove(&client_id);
            renet.remove_connection(client_id);
            Handled::sent(payload.map_or(0, |p| {
                send(addr, p);
                p.len()
            }))
        }
    }
}
