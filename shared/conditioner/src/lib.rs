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
mod link;

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::core::Core;
pub use crate::link::{Conditions, Stats, Traffic};

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

#[cfg(test)]
mod tests;
