//! The server's side of the UDP transport: every datagram is checked, rate-limited and only then handed to
//! netcode; every decrypted payload is unbundled and each of its packets checked before renet sees it.
//!
//! [`ServerIntake`] owns no socket: [`ServerIntake::receive`] takes one datagram and the caller's send
//! function, so tests and the fuzz target drive it in memory exactly as the game's socket loop does.

use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};
use std::time::Duration;

use renet::RenetServer;
use renetcode::{NETCODE_USER_DATA_BYTES, NetcodeServer, ServerConfig, ServerResult};

use crate::bundle::Bundler;
use crate::datagram::DatagramRefusal;
use crate::datagram::{Direction, PacketKind, check_datagram};
use crate::error::PayloadRefusal;
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
    /// renet packets per connected client, whatever datagrams carry them ([`crate::bundle`]); default
    /// 1000/s, 1000 at once (a player sends ~150/s).
    pub packets_per_client: Rate,
    /// Largest client message in slices of 1200 bytes; default 32 (the largest a client sends is ~5 KB).
    pub max_slices: u64,
    /// Refused payloads a client may send (leaking one a second) before it is disconnected; default 20.
    pub refused_payloads_limit: f64,
    /// Addresses whose request rate is tracked at once; default 4096.
    pub tracked_addresses: usize,
}

impl IntakeLimits {
    /// The rate at which refused payloads are forgiven: one a second, `refused_payloads_limit` at once.
    fn refusal_rate(&self) -> Rate {
        Rate::new(1.0, self.refused_payloads_limit)
    }
}

impl Default for IntakeLimits {
    fn default() -> Self {
        Self {
            requests_per_address: Rate::new(10.0, 10.0),
            requests_total: Rate::new(500.0, 500.0),
            packets_per_client: Rate::new(1000.0, 1000.0),
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
    packets: Bucket,
    /// Refused payloads it may still send; empty means disconnect.
    refusals: Bucket,
    expelled: bool,
}

/// What acting on netcode's results reads and changes: the connected clients, the clock, the counts.
#[derive(Debug)]
struct Peers {
    limits: IntakeLimits,
    now_s: f64,
    connections: HashMap<u64, Connection>,
    stats: IntakeStats,
    /// The last clients that went other than by falling silent, and how.
    departures: std::collections::VecDeque<(u64, Departure)>,
}

/// Departures remembered (the newest kept): enough for the game to ask about the clients that just went.
const DEPARTURES_KEPT: usize = 64;

/// How a connection ended other than by falling silent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Departure {
    /// The client sent netcode's disconnect packet: it closed the connection itself.
    Goodbye,
    /// The server let it go: the intake expelled it for refused payloads, renet for a protocol error, or
    /// the game asked.
    LetGo,
}

/// Checks and forwards every datagram of the game socket.
#[derive(Debug)]
pub struct ServerIntake {
    netcode: NetcodeServer,
    requests: KeyedLimiter<IpAddr>,
    peers: Peers,
    log: RefusalLog,
    bundler: Bundler,
}

/// Where the intake sends datagrams: (destination, bytes).
pub type Send<'a> = dyn FnMut(SocketAddr, &[u8]) + 'a;

impl ServerIntake {
    /// An intake around a netcode server made from `config`.
    pub fn new(config: ServerConfig, limits: IntakeLimits) -> Self {
        Self {
            netcode: NetcodeServer::new(config),
            requests: KeyedLimiter::new(limits.requests_per_address, limits.requests_total, limits.tracked_addresses),
            peers: Peers {
                limits,
                now_s: 0.0,
                connections: HashMap::new(),
                stats: IntakeStats::default(),
                departures: std::collections::VecDeque::with_capacity(DEPARTURES_KEPT),
            },
            log: RefusalLog::new("heist_transport::server", "UDP intake"),
            bundler: Bundler::new(),
        }
    }

    /// Advances time by `dt` (netcode expires pending clients with it).
    pub fn advance(&mut self, dt: Duration) {
        self.peers.now_s += dt.as_secs_f64();
        self.netcode.update(dt);
        self.log.roll(self.peers.now_s);
    }

    /// Takes one datagram from `from`: checks it, lets netcode process it, passes a payload on to renet.
    pub fn receive(
        &mut self,
        from: SocketAddr,
        datagram: &mut [u8],
        renet: &mut RenetServer,
        send: &mut Send<'_>,
    ) -> Result<(), Refused> {
        self.peers.stats.datagrams += 1;
        self.peers.stats.bytes_in += datagram.len() as u64;
        let refusal = match self.admit(from, datagram) {
            Ok(kind) => {
                let result = self.netcode.process_packet(from, datagram);
                let ignored = matches!(result, ServerResult::None);
                // Netcode ends a connection on a received datagram only for the client's own disconnect
                // packet (timeouts and the server's disconnects come from `update`).
                if let ServerResult::ClientDisconnected { client_id, .. } = &result {
                    self.peers.departed(*client_id, Departure::Goodbye);
                }
                return match self.peers.handle(result, renet, send) {
                    Some((client_id, refusal)) => Err(self.refused_payload(client_id, refusal, renet)),
                    // netcode says why only in its own log (`RUST_LOG=renetcode=debug`); a request or a
                    // payload that led nowhere was turned away: a bad, expired or replayed token, a full
                    // server, a packet that failed authentication.
                    None if ignored && matches!(kind, PacketKind::ConnectionRequest | PacketKind::Payload) => {
                        self.peers.stats.refused_by_netcode += 1;
                        let why = format!("netcode turned away a {kind:?} (see RUST_LOG=renetcode=debug)");
                        self.log.refused(from, &why, self.peers.now_s);
                        Err(Refused::Netcode(kind))
                    }
                    None => Ok(()),
                };
            }
            Err(r) => r,
        };
        self.peers.stats.refused_datagrams += 1;
        self.log.refused(from, &refusal, self.peers.now_s);
        Err(Refused::Datagram(refusal))
    }

    /// Header check and, for a connection request, the request rate.
    fn admit(&mut self, from: SocketAddr, datagram: &[u8]) -> Result<PacketKind, DatagramRefusal> {
        let kind = check_datagram(datagram, Direction::ToServer)?;
        if kind == PacketKind::ConnectionRequest && !self.requests.take(address_key(from.ip()), self.peers.now_s) {
            return Err(DatagramRefusal::RateLimited);
        }
        Ok(kind)
    }

    /// Logs a refused payload and disconnects its client once it has sent too many.
    fn refused_payload(&mut self, client_id: u64, refusal: PayloadRefusal, renet: &mut RenetServer) -> Refused {
        let Peers { limits, now_s, connections, stats, .. } = &mut self.peers;
        stats.refused_payloads += 1;
        let Some(c) = connections.get_mut(&client_id) else { return Refused::Payload(refusal) };
        self.log.refused(c.addr, &Refused::Payload(refusal), *now_s);
        if !c.refusals.take(limits.refusal_rate(), *now_s) && !c.expelled {
            c.expelled = true;
            stats.expelled += 1;
            log::warn!("UDP intake: disconnecting client {client_id} at {}: too many refused payloads", c.addr);
            renet.disconnect(client_id);
        }
        Refused::Payload(refusal)
    }

    /// Keep-alives, timeouts and the disconnections renet asked for; call once per frame after receiving.
    pub fn update(&mut self, renet: &mut RenetServer, send: &mut Send<'_>) {
        for id in self.netcode.clients_id() {
            self.peers.handle(self.netcode.update_client(id), renet, send);
        }
        for id in renet.disconnections_id() {
            self.peers.departed(id, Departure::LetGo);
            self.peers.handle(self.netcode.disconnect(id), renet, send);
        }
    }

    /// Sends renet's packets for every connected client, bundled: one datagram for all that fit.
    pub fn send_packets(&mut self, renet: &mut RenetServer, send: &mut Send<'_>) {
        let Self { netcode, peers, bundler, .. } = self;
        for id in renet.clients_id() {
            let Ok(packets) = renet.get_packets_to_send(id) else { continue };
            let sealed = bundler.pack(&packets, |bundle| {
                let (addr, bytes) = netcode.generate_payload_packet(id, bundle)?;
                peers.stats.bytes_out += bytes.len() as u64;
                send(addr, bytes);
                Ok::<_, renetcode::NetcodeError>(())
            });
            if let Err(e) = sealed {
                log::error!("UDP intake: cannot encrypt a packet for client {id}: {e}");
            }
        }
    }

    /// Disconnects every client at once (the server is stopping).
    pub fn disconnect_all(&mut self, renet: &mut RenetServer, send: &mut Send<'_>) {
        for id in self.netcode.clients_id() {
            self.peers.handle(self.netcode.disconnect(id), renet, send);
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

    /// Clients netcode holds a slot for (every slot is walked each frame, taken or not).
    pub fn max_clients(&self) -> usize {
        self.netcode.max_clients()
    }

    /// How `client_id` went, when it was one of the last 64 to go other than by falling silent: `None` for
    /// a connection that timed out (or one this intake never saw go).
    pub fn departure(&self, client_id: u64) -> Option<Departure> {
        self.peers.departures.iter().find(|(id, _)| *id == client_id).map(|(_, d)| *d)
    }

    /// Counts so far.
    pub fn stats(&self) -> IntakeStats {
        self.peers.stats
    }
}

impl Connection {
    fn new(addr: SocketAddr, limits: &IntakeLimits, now_s: f64) -> Self {
        Self {
            addr,
            slices: SliceGuard::new(limits.max_slices),
            packets: Bucket::full(limits.packets_per_client, now_s),
            refusals: Bucket::full(limits.refusal_rate(), now_s),
            expelled: false,
        }
    }

    /// Checks one renet packet of a decrypted payload: the connection's packet rate, then its slices.
    fn check(&mut self, packet: &[u8], limits: &IntakeLimits, now_s: f64) -> Result<(), PayloadRefusal> {
        if !self.packets.take(limits.packets_per_client, now_s) {
            return Err(PayloadRefusal::RateLimited);
        }
        self.slices.check(packet)
    }
}

impl Peers {
    fn departed(&mut self, client_id: u64, how: Departure) {
        if self.departures.len() == DEPARTURES_KEPT {
            self.departures.pop_front();
        }
        self.departures.push_back((client_id, how));
    }

    /// Acts on one netcode result: sends what it says to send, passes a checked payload to renet; returns
    /// the payload refusal, if that is what it came to.
    fn handle(
        &mut self,
        result: ServerResult<'_, '_>,
        renet: &mut RenetServer,
        send: &mut Send<'_>,
    ) -> Option<(u64, PayloadRefusal)> {
        let mut sent = |addr, bytes: &[u8]| {
            self.stats.bytes_out += bytes.len() as u64;
            send(addr, bytes);
        };
        match result {
            ServerResult::None => {}
            ServerResult::PacketToSend { addr, payload } => sent(addr, payload),
            ServerResult::Payload { client_id, payload } => {
                let connection = self.connections.get_mut(&client_id)?;
                let delivered = crate::bundle::unbundle(payload).and_then(|packets| {
                    for packet in packets {
                        connection.check(packet, &self.limits, self.now_s)?;
                        // Only fails for an unknown client, which netcode just vouched for.
                        let _ = renet.process_packet_from(packet, client_id);
                    }
                    Ok(())
                });
                if let Err(r) = delivered {
                    return Some((client_id, r));
                }
            }
            ServerResult::ClientConnected { client_id, addr, payload, .. } => {
                log::info!("UDP intake: client {client_id} connected from {addr}");
                sent(addr, payload);
                self.connections.insert(client_id, Connection::new(addr, &self.limits, self.now_s));
                renet.add_connection(client_id);
            }
            ServerResult::ClientDisconnected { client_id, addr, payload } => {
                log::info!("UDP intake: client {client_id} at {addr} disconnected");
                if let Some(p) = payload {
                    sent(addr, p);
                }
                self.connections.remove(&client_id);
                renet.remove_connection(client_id);
            }
        }
        None
    }
}
