//! What a link does to datagrams, each way, and what went through it.

use std::time::Duration;

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
