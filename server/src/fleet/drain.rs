//! The graceful drain: asked for by SIGTERM/SIGINT ([`super::signals`]) or by Agones (the game server
//! marked `Shutdown`), carried out by the game loop. From the first tick of a drain no session is
//! created (the token endpoint refuses `Create` with [`JoinRefusal::Draining`]), every session's players
//! are told, sessions not playing a heist close at once, running heists play on until their result or
//! the drain limit, and the app exits 0 once no session is left.
//!
//! [`JoinRefusal::Draining`]: heist_shared::protocol::join::JoinRefusal::Draining

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use bevy::prelude::*;

use super::Fleet;
use crate::net::NetSettings;
use crate::session::Session;

/// How long a drain waits for running heists unless told otherwise: the museum's whole heist (10 min)
/// and a minute more. Kubernetes' `terminationGracePeriodSeconds` must be longer (docs/deploy.md).
pub const DEFAULT_DRAIN_LIMIT: Duration = Duration::from_secs(660);

/// A request to drain, shared by whoever may ask and the game loop (cheap to clone).
#[derive(Clone, Debug, Default)]
pub struct Drain(Arc<AtomicBool>);

impl Drain {
    /// Asks for a drain; true for the first request, false when one was already asked for.
    pub fn request(&self) -> bool {
        !self.0.swap(true, Ordering::SeqCst)
    }

    /// True once a drain was asked for.
    pub fn is_requested(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

/// The game loop's side of a drain.
#[derive(Resource, Debug, Default)]
pub(super) struct DrainProgress {
    started: Option<Instant>,
    cut: bool,
    exited: bool,
}

/// Carries out a requested drain, each tick.
pub(super) fn drain_sessions(
    fleet: Res<Fleet>,
    settings: Res<NetSettings>,
    mut progress: ResMut<DrainProgress>,
    mut sessions: Query<&mut Session>,
    mut exit: MessageWriter<AppExit>,
) {
    if !fleet.drain.is_requested() || progress.exited {
        return;
    }
    let limit = fleet.drain_limit;
    let started = *progress.started.get_or_insert_with(|| {
        settings.registry.stop_opening();
        fleet.metrics.draining.set(1);
        let running = sessions.iter().filter(|s| s.game.phase == heist_shared::protocol::Phase::Heist).count();
        info!(
            target: "fleet",
            event = "drain_started",
            sessions = sessions.iter().count(),
            heists = running,
            limit_s = limit.as_secs(),
            "draining: no new sessions; {running} heists under way may finish within {} s",
            limit.as_secs()
        );
        Instant::now()
    });
    let waited = started.elapsed();
    let within_s = limit.saturating_sub(waited).as_secs().max(1) as u32;
    for mut session in &mut sessions {
        session.game.drain(within_s);
    }
    if waited >= limit && !progress.cut {
        progress.cut = true;
        let open = sessions.iter().filter(|s| !s.game.closed).count();
        warn!(target: "fleet", event = "drain_limit", sessions = open, "the drain limit is reached: closing {open} sessions");
        for mut session in &mut sessions {
            session.game.closed = true;
        }
    }
    if sessions.is_empty() && settings.registry.is_empty() {
        progress.exited = true;
        info!(
            target: "fleet",
            event = "drained",
            after_s = waited.as_secs_f64(),
            "drained after {:.1} s: every session is over",
            waited.as_secs_f64()
        );
        exit.write(AppExit::Success);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_first_request_starts_a_drain() {
        let d = Drain::default();
        assert!(!d.is_requested());
        assert!(d.clone().request(), "the first request (from a clone)");
        assert!(!d.request(), "the second is not a new drain");
        assert!(d.is_requested());
    }
}
