//! What the endpoint's connection tasks share: its configuration and limits, the wrong-code counts, the
//! refusal log, and the open connections each task leaves when it ends.

use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use heist_transport::throttle::RefusalLog;

use super::connections::Connections;
use super::guesses::{GuessLimits, Guesses};
use crate::net::registry::{CreateLimits, Registry};

/// The endpoint's limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TokenLimits {
    /// Whole exchange, from accept to the last byte; default 2 s.
    pub deadline: Duration,
    /// Open connections per address (IPv6: per /64); default 32, the oldest gives way.
    pub per_address: usize,
    /// Open connections in all; default 256, the oldest gives way.
    pub total: usize,
    /// Wrong codes.
    pub guesses: GuessLimits,
    /// New sessions.
    pub creates: CreateLimits,
}

/// How many sessions a `serve` hosts at once unless told otherwise.
pub const DEFAULT_MAX_SESSIONS: usize = 96;

impl Default for TokenLimits {
    fn default() -> Self {
        Self {
            deadline: Duration::from_secs(2),
            per_address: 32,
            total: 256,
            guesses: GuessLimits::default(),
            creates: CreateLimits::default(),
        }
    }
}

/// What the endpoint needs to mint tokens.
#[derive(Clone)]
pub struct TokenConfig {
    /// The sessions, their codes and seats.
    pub registry: Registry,
    /// Netcode private key shared with the game server.
    pub private_key: [u8; 32],
    /// Each shard's public UDP address (must equal that shard's `public_addresses`): a session's tokens
    /// name its shard's.
    pub server_addrs: Vec<SocketAddr>,
    /// Limits.
    pub limits: TokenLimits,
    /// Where refusals are counted.
    pub metrics: crate::fleet::Metrics,
}

/// Everything the connection tasks share.
pub(super) struct Shared {
    pub(super) config: TokenConfig,
    pub(super) started: Instant,
    pub(super) guesses: Mutex<Guesses>,
    pub(super) log: Mutex<RefusalLog>,
}

pub(super) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl Shared {
    pub(super) fn now_s(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    pub(super) fn refused(&self, peer: SocketAddr, reason: &dyn std::fmt::Display) {
        lock(&self.log).refused(peer, reason, self.now_s());
    }
}

/// Removes a connection from the open set when its task ends, however it ends.
pub(super) struct Closer {
    pub(super) open: Arc<Mutex<Connections<tokio::task::AbortHandle>>>,
    pub(super) id: u64,
}

impl Drop for Closer {
    fn drop(&mut self) {
        lock(&self.open).close(self.id);
    }
}
