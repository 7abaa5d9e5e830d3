//! Running on a fleet (docs/deploy.md): what an orchestrator needs of the server.
//!
//! Always present in a built server ([`Fleet`], [`FleetPlugin`]): the heartbeat every update stamps,
//! the metrics every part counts into, the drain request and its handling in the game loop. Started on
//! demand (`FleetServices::start`): the health and metrics endpoint (`--metrics`), the Agones link
//! (`--agones`) and the termination signals (the binary's `serve` and `host`). These link hyper, tonic and
//! the Agones SDK, so they come with the `fleet` feature (on by default; the clients, which host a game on
//! a thread, leave it off).

#[cfg(feature = "fleet")]
pub mod agones;
pub mod drain;
pub mod health;
#[cfg(feature = "fleet")]
pub mod http;
pub mod metrics;
mod plugin;
#[cfg(feature = "fleet")]
mod services;
#[cfg(feature = "fleet")]
pub mod signals;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use bevy::prelude::*;

pub use drain::{DEFAULT_DRAIN_LIMIT, Drain};
pub use health::{Heartbeat, STALL_AFTER};
pub use metrics::Metrics;
pub use plugin::FleetPlugin;
pub(crate) use plugin::thread_cpu;
#[cfg(feature = "fleet")]
pub use services::{FleetOptions, FleetServices};

/// The fleet side of a server: shared with the threads that report on it (cheap to clone).
#[derive(Resource, Clone)]
pub struct Fleet {
    /// Stamped by every update of the game loop.
    pub heartbeat: Heartbeat,
    /// How long without an update counts as stalled.
    pub stall_after: Duration,
    /// Everything counted.
    pub metrics: Metrics,
    /// Set to start a drain.
    pub drain: Drain,
    /// How long a drain waits for running heists.
    pub drain_limit: Duration,
    fatal: Arc<Mutex<Option<String>>>,
}

impl Fleet {
    /// A fleet side for a server of at most `max_sessions`, with fresh metrics and no drain asked for.
    pub fn new(max_sessions: usize, drain_limit: Duration, stall_after: Duration) -> Self {
        let metrics = Metrics::new();
        metrics.sessions_max.set(max_sessions as i64);
        Self {
            heartbeat: Heartbeat::default(),
            stall_after,
            metrics,
            drain: Drain::default(),
            drain_limit,
            fatal: Arc::default(),
        }
    }

    /// Healthy (the loop runs and no drain is under way), with a line saying how it is.
    pub fn health(&self) -> (bool, String) {
        let sessions = self.metrics.sessions.get();
        if self.heartbeat.stalled(self.stall_after) {
            let age = self.heartbeat.age().map_or_else(|| "never".into(), |a| format!("{:.1} s ago", a.as_secs_f64()));
            (false, format!("stalled: the game loop last updated {age}"))
        } else if self.drain.is_requested() {
            (false, format!("draining: {sessions} sessions left"))
        } else {
            (true, format!("ok: {sessions} sessions, {} players", self.metrics.players.get()))
        }
    }

    /// A helper thread failed in a way the server cannot run on (the Agones sidecar is unreachable):
    /// the game loop exits with an error at its next update.
    pub fn fail(&self, why: String) {
        *self.fatal.lock().unwrap_or_else(|p| p.into_inner()) = Some(why);
    }

    /// Why the server had to stop, if it had to.
    pub fn failure(&self) -> Option<String> {
        self.fatal.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }
}
