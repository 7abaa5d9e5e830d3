//! What both relays share: the sockets, the held datagrams, the dice.

use std::net::{SocketAddr, UdpSocket};
use std::time::Duration;

use crate::link::{Conditions, Stats};

/// Largest datagram relayed, bytes (ours are at most 1400).
const BUFFER: usize = 2048;
/// Datagrams held at most; beyond, the newest is dropped (a test flooding itself stays bounded).
const MAX_HELD: usize = 65_536;

/// One held datagram.
struct Held {
    due: Duration,
    bytes: Vec<u8>,
    client: usize,
    upstream: bool,
}

pub(crate) struct Core {
    pub(crate) addr: SocketAddr,
    pub(crate) stats: Stats,
    front: UdpSocket,
    /// Where upstream datagrams go, once known.
    pub(crate) server: Option<SocketAddr>,
    /// Each client's address and the socket it reaches the server from (so the server sees each client
    /// at an address of its own).
    clients: Vec<(SocketAddr, UdpSocket)>,
    held: Vec<Held>,
    conditions: Conditions,
    rng: u64,
    buffer: Box<[u8; BUFFER]>,
}

impl Core {
    pub(crate) fn bind(conditions: Conditions, seed: u64) -> std::io::Result<Self> {
        let front = loopback()?;
        Ok(Self {
            addr: front.local_addr()?,
            stats: Stats::default(),
            front,
            server: None,
            clients: Vec::new(),
            held: Vec::new(),
            conditions,
            // xorshift must not start at 0.
            rng: seed | 1,
            buffer: Box::new([0; BUFFER]),
        })
    }

    /// A uniform number in 0..1.
    fn roll(&mut self) -> f64 {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        (self.rng >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Reads every waiting datagram from both sides and holds (or drops) each.
    pub(crate) fn take_in(&mut self, now: Duration) -> std::io::Result<()> {
        loop {
            match self.front.recv_from(&mut self.buffer[..]) {
                Ok((n, from)) => {
                    let client = match self.clients.iter().position(|(a, _)| *a == from) {
                        Some(i) => i,
                        None => {
                            self.clients.push((from, loopback()?));
                            self.clients.len() - 1
                        }
                    };
                    self.hold(now, n, client, true);
                }
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                // A client that went away makes the next read report it (on some systems): not ours to fail.
                Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => {}
                Err(e) => return Err(e),
            }
        }
        for client in 0..self.clients.len() {
            while let Ok((n, _)) = self.clients[client].1.recv_from(&mut self.buffer[..]) {
                self.hold(now, n, client, false);
            }
        }
        Ok(())
    }

    fn hold(&mut self, now: Duration, len: usize, client: usize, upstream: bool) {
        let lost = self.conditions.loss > 0.0 && self.roll() < self.conditions.loss;
        let traffic = if upstream { &mut self.stats.up } else { &mut self.stats.down };
        if lost || self.held.len() >= MAX_HELD {
            traffic.dropped += 1;
            return;
        }
        let extra = self.conditions.jitter.mul_f64(self.roll());
        let bytes = self.buffer[..len].to_vec();
        self.held.push(Held { due: now + self.conditions.latency + extra, bytes, client, upstream });
    }

    #[cfg(test)]
    pub(crate) fn held(&self) -> usize {
        self.held.len()
    }

    /// Sends every datagram due by `now`, oldest due first.
    pub(crate) fn send_due(&mut self, now: Duration) {
        self.held.sort_by_key(|h| h.due);
        let due = self.held.iter().take_while(|h| h.due <= now).count();
        for h in self.held.drain(..due) {
            let (client, up) = &self.clients[h.client];
            let sent = match (h.upstream, self.server) {
                (true, Some(server)) => up.send_to(&h.bytes, server),
                (true, None) => continue,
                (false, _) => self.front.send_to(&h.bytes, *client),
            };
            let traffic = if h.upstream { &mut self.stats.up } else { &mut self.stats.down };
            if sent.is_ok() {
                traffic.passed += 1;
                traffic.bytes += h.bytes.len() as u64;
            }
        }
    }
}

/// A bound loopback UDP socket that does not block.
fn loopback() -> std::io::Result<UdpSocket> {
    let socket = UdpSocket::bind("127.0.0.1:0")?;
    socket.set_nonblocking(true)?;
    Ok(socket)
}
