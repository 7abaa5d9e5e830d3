//! Whether the game loop is alive: every update stamps a heartbeat; the health endpoint and the Agones
//! health pings read its age from their own threads, so a stuck loop stops them without taking part.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// How long without an update counts as stalled unless told otherwise: well above the slowest tick a
/// loaded server takes (tens of ms), well below Agones' default health window (3 × 5 s).
pub const STALL_AFTER: Duration = Duration::from_secs(5);

/// The game loop's last update, shared (cheap to clone).
#[derive(Clone, Debug)]
pub struct Heartbeat {
    epoch: Instant,
    /// Microseconds from `epoch` to the last beat; 0 before the first.
    last_us: Arc<AtomicU64>,
}

impl Default for Heartbeat {
    fn default() -> Self {
        Self { epoch: Instant::now(), last_us: Arc::new(AtomicU64::new(0)) }
    }
}

impl Heartbeat {
    /// The loop is alive now.
    pub fn beat(&self) {
        let us = self.epoch.elapsed().as_micros().max(1) as u64;
        self.last_us.store(us, Ordering::Relaxed);
    }

    /// Time since the last beat; `None` before the first.
    pub fn age(&self) -> Option<Duration> {
        match self.last_us.load(Ordering::Relaxed) {
            0 => None,
            us => Some(self.epoch.elapsed().saturating_sub(Duration::from_micros(us))),
        }
    }

    /// True when the loop has not updated for `after` (or never did).
    pub fn stalled(&self, after: Duration) -> bool {
        self.age().is_none_or(|age| age > after)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_heartbeat_is_stalled_before_its_first_beat_and_once_beats_stop() {
        let h = Heartbeat::default();
        assert!(h.stalled(Duration::from_secs(60)), "never beat");
        h.clone().beat();
        assert!(!h.stalled(Duration::from_secs(60)), "a clone's beat counts");
        std::thread::sleep(Duration::from_millis(30));
        assert!(h.stalled(Duration::from_millis(10)));
        assert!(h.age().is_some_and(|a| a >= Duration::from_millis(30)));
    }
}
