//! A link conditioner for tests. You need this crate to play a heist, or any exchange over UDP, through a
//! bad network on loopback: clients send to the relay's address (the server advertises it), and every
//! datagram, each way, is held for the link's latency plus a random jitter, or dropped — from a fixed
//! seed, so a run repeats.
//!
//! Two ways to run it: [`Relay`] on its own thread, in wall-clock time, for a test that runs in real
//! time; [`SteppedRelay`] driven by the test between its app updates, in the time the test counts, so a
//! heist stepped faster than real time sees the same latency in game time (and the outcome does not depend
//! on the machine's speed). `tc netem` is not available on these machines (see facts.md).
#![warn(missing_docs)]

mod core;

use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::core::Core;

/// How a link behaves, each way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conditions {
    /// Base delay of every datagram.
    pub latency: Duration,
    /// Extra delay, uniform up to this (datagrams can overtake each other).
    pub jitter: Duration,
    /// Probability a datagram is lost, 0..=1.
    pub loss: f64,
}

impl Conditions {
    /// A perfect link.
    pub const PERFECT: Self = Self { latency: Duration::ZERO, jitter: Duration::ZERO, loss: 0.0 };
    /// lightyear's "good" preset: 40 ms, 6 ms jitter, 0.2 % loss.
    pub const GOOD: Self = Self { latency: Duration::from_millis(40), jitter: Duration::from_millis(6), loss: 0.002 };
    /// lightyear's "average" preset: 100 ms, 15 ms jitter, 2 % loss.
    pub const AVERAGE: Self =
        Self { latency: Duration::from_millis(100), jitter: Duration::from_millis(15), loss: 0.02 };
    /// lightyear's "poor" preset: 200 ms, 30 ms jitter, 10 % loss.
    pub const POOR: Self = Self { latency: Duration::from_millis(200), jitter: Duration::from_millis(30), loss: 0.10 };

    /// Only a fixed delay.
    pub const fn delay(latency: Duration) -> Self {
        Self { latency, jitter: Duration::ZERO, loss: 0.0 }
    }
}

/// What went through a relay, per direction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Traffic {
    /// Datagrams passed on.
    pub passed: u64,
    /// Datagrams dropped by the loss.
    pub dropped: u64,
    /// Bytes passed on.
    pub bytes: u64,
}

/// What went through a relay both ways.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Clients to the server.
    pub up: Traffic,
    /// The server to clients.
    pub down: Traffic,
}

/// A relay the test drives: call [`SteppedRelay::advance`] once per tick, after the apps updated.
pub struct SteppedRelay {
    core: Core,
    now: Duration,
}

impl SteppedRelay {
    /// Binds the front socket on loopback: the address to advertise to clients (then
    /// [`SteppedRelay::forward_to`] the server).
    pub fn bind(conditions: Conditions, seed: u64) -> std::io::Result<Self> {
        Ok(Self { core: Core::bind(conditions, seed)?, now: Duration::ZERO })
    }

    /// Where clients send.
    pub fn addr(&self) -> SocketAddr {
        self.core.addr
    }

    /// Relays to `server` (until then, what clients send is held and then dropped as undeliverable).
    pub fn forward_to(&mut self, server: SocketAddr) {
        self.core.server = Some(server);
    }

    /// Takes in what arrived since the last call (as sent now), moves the relay's clock on by `dt` and
    /// passes on what is due by then.
    pub fn advance(&mut self, dt: Duration) -> std::io::Result<()> {
        self.core.take_in(self.now)?;
        self.now += dt;
        self.core.send_due(self.now);
        Ok(())
    }

    /// Traffic so far.
    pub fn stats(&self) -> Stats {
        self.core.stats
    }

    #[cfg(test)]
    fn held(&self) -> usize {
        self.core.held()
    }
}

/// A relay on its own thread, in wall-clock time (at most ten minutes); stops when dropped.
pub struct Relay {
    /// Where clients send.
    pub addr: SocketAddr,
    core: Option<Core>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Stats>>,
}

impl Relay {
    /// Binds the front socket on loopback: the address to advertise to clients (then
    /// [`Relay::start`] towards the server).
    pub fn bind(conditions: Conditions, seed: u64) -> std::io::Result<Self> {
        let core = Core::bind(conditions, seed)?;
        Ok(Self { addr: core.addr, core: Some(core), stop: Arc::new(AtomicBool::new(false)), thread: None })
    }

    /// Starts relaying to `server` on the relay's thread (once; a second call does nothing).
    pub fn start(&mut self, server: SocketAddr) -> std::io::Result<()> {
        let Some(mut core) = self.core.take() else { return Ok(()) };
        core.server = Some(server);
        let flag = self.stop.clone();
        self.thread = Some(std::thread::Builder::new().name("link-conditioner".into()).spawn(move || {
            let started = Instant::now();
            while !flag.load(Ordering::Relaxed) && started.elapsed() < Duration::from_secs(600) {
                let now = started.elapsed();
                if core.take_in(now).is_err() {
                    break;
                }
                core.send_due(now);
                std::thread::sleep(Duration::from_micros(300));
            }
            core.stats
        })?);
        Ok(())
    }

    /// Stops the relay and returns its traffic.
    pub fn stop(mut self) -> Stats {
        self.halt()
    }

    fn halt(&mut self) -> Stats {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.take().and_then(|t| t.join().ok()).unwrap_or_default()
    }
}

impl Drop for Relay {
    fn drop(&mut self) {
        self.halt();
    }
}

/// A bound loopback UDP socket that does not block.
fn loopback() -> std::io::Result<UdpSocket> {
    let socket = UdpSocket::bind("127.0.0.1:0")?;
    socket.set_nonblocking(true)?;
    Ok(socket)
}

#[cfg(test)]
mod tests;
