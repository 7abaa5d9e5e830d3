//! The graceful drain: asked for by SIGTERM/SIGINT ([`super::signals`]) or by Agones (the game server
//! marked `Shutdown`), carried out by the game loop (`plugin.rs`). From the first tick of a drain no session is
//! created (the token endpoint refuses `Create` with [`JoinRefusal::Draining`]), every session's players
//! are told, sessions not playing a heist close at once, running heists play on until their result or
//! the drain limit, and the app exits 0 once no session is left.
//!
//! [`JoinRefusal::Draining`]: heist_shared::protocol::join::JoinRefusal::Draining

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

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
