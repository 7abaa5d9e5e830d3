//! What the server counts, in the Prometheus text format (`GET /metrics`, [`super::http`]).
//!
//! The handles are atomics shared by clones: the game loop sets the gauges and observes each tick
//! ([`super::FleetPlugin`]), the token endpoint counts its refusals, the network side counts message
//! refusals and resumes. Nothing is collected on a scrape but the encoding.

use std::sync::Arc;
use std::sync::atomic::AtomicU64;

use bevy::prelude::Resource;
use prometheus_client::encoding::EncodeLabelSet;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::Registry;

/// Which request was refused, and why (a fixed set of names: never a client's text).
#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct Refused {
    /// `join` (the token endpoint's answer), `exchange` (a connection that broke off or sent garbage)
    /// or `message` (a game message the rules refused).
    pub stage: &'static str,
    /// The refusal's kind (`wrong_code`, `full`, `draining`, `too_fast`, …).
    pub reason: &'static str,
}

/// Every metric of the server (cheap to clone; clones share the values).
#[derive(Resource, Clone)]
pub struct Metrics {
    registry: Arc<Registry>,
    /// Sessions open now.
    pub sessions: Gauge,
    /// `--max-sessions`.
    pub sessions_max: Gauge,
    /// Sessions created since start.
    pub sessions_created: Counter,
    /// Sessions ended since start.
    pub sessions_ended: Counter,
    /// Players connected and admitted now.
    pub players: Gauge,
    /// Seats kept for players who dropped, now.
    pub seats_kept: Gauge,
    /// Seats taken back by players who dropped.
    pub resumes: Counter,
    /// Seconds one shard's update in the game loop took (its sessions' tick, the network in and out).
    pub tick_seconds: Histogram,
    /// CPU seconds the game loop's updates took (the loop thread's CPU clock, every shard's update): its
    /// rate divided by the ticks (60 a second) and the sessions open is a session's cost per tick.
    pub tick_cpu_seconds: Counter<f64, AtomicU64>,
    /// UDP payload bytes read from the game socket.
    pub bytes_received: Counter,
    /// UDP payload bytes sent on it.
    pub bytes_sent: Counter,
    /// Refused requests by stage and reason.
    pub refused: Family<Refused, Counter>,
    /// 1 while the server drains (shutting down), else 0.
    pub draining: Gauge,
}

impl Default for Metrics {
    fn default() -> Self {
        Self::new()
    }
}

impl Metrics {
    /// Every metric at zero, registered under the `heist_` prefix.
    pub fn new() -> Self {
        let mut registry = Registry::with_prefix("heist");
        let m = Self {
            registry: Arc::new(Registry::default()),
            sessions: Gauge::default(),
            sessions_max: Gauge::default(),
            sessions_created: Counter::default(),
            sessions_ended: Counter::default(),
            players: Gauge::default(),
            seats_kept: Gauge::default(),
            resumes: Counter::default(),
            // 0.25 ms to ~0.5 s: a tick is budgeted 16.7 ms.
            tick_seconds: Histogram::new(exponential_buckets(0.000_25, 2.0, 12)),
            tick_cpu_seconds: Counter::default(),
            bytes_received: Counter::default(),
            bytes_sent: Counter::default(),
            refused: Family::default(),
            draining: Gauge::default(),
        };
        registry.register("sessions", "Sessions open now", m.sessions.clone());
        registry.register("sessions_max", "Sessions the server hosts at most (--max-sessions)", m.sessions_max.clone());
        registry.register("sessions_created", "Sessions created", m.sessions_created.clone());
        registry.register("sessions_ended", "Sessions ended", m.sessions_ended.clone());
        registry.register("players", "Players connected and admitted now", m.players.clone());
        registry.register("seats_kept", "Seats kept for players whose connection dropped", m.seats_kept.clone());
        registry.register("resumes", "Seats taken back by players whose connection dropped", m.resumes.clone());
        registry.register("tick_seconds", "Time of one shard's update in the game loop", m.tick_seconds.clone());
        registry.register(
            "tick_cpu_seconds",
            "CPU time of the game loop's updates (the loop thread's clock)",
            m.tick_cpu_seconds.clone(),
        );
        registry.register("received_bytes", "UDP payload bytes read from the game socket", m.bytes_received.clone());
        registry.register("sent_bytes", "UDP payload bytes sent on the game socket", m.bytes_sent.clone());
        registry.register("refused", "Refused requests, by stage and reason", m.refused.clone());
        registry.register("draining", "1 while the server drains before it exits", m.draining.clone());
        Self { registry: Arc::new(registry), ..m }
    }

    /// Counts one refused request.
    pub fn refuse(&self, stage: &'static str, reason: &'static str) {
        self.refused.get_or_create(&Refused { stage, reason }).inc();
    }

    /// Everything, in the Prometheus text exposition format.
    pub fn encode(&self) -> String {
        let mut text = String::new();
        // Writing to a String cannot fail.
        let _ = prometheus_client::encoding::text::encode(&mut text, &self.registry);
        text
    }
}

/// The value of the sample `name` (with its labels, as written: `heist_refused_total{stage="join",…}`)
/// in a text exposition, for tests and tools that read a scrape.
pub fn sample(text: &str, name: &str) -> Option<f64> {
    text.lines().find_map(|line| {
        let rest = line.strip_prefix(name)?;
        rest.strip_prefix(' ')?.split_whitespace().next()?.parse().ok()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_exposition_names_every_metric_and_carries_the_values() {
        let m = Metrics::new();
        m.sessions.set(3);
        m.sessions_created.inc_by(4);
        m.refuse("join", "wrong_code");
        m.refuse("join", "wrong_code");
        m.refuse("message", "too_fast");
        m.tick_seconds.observe(0.002);
        m.tick_cpu_seconds.inc_by(0.0015);
        let text = m.encode();
        assert_eq!(sample(&text, "heist_sessions"), Some(3.0), "{text}");
        assert_eq!(sample(&text, "heist_sessions_created_total"), Some(4.0), "{text}");
        assert_eq!(sample(&text, r#"heist_refused_total{stage="join",reason="wrong_code"}"#), Some(2.0), "{text}");
        assert_eq!(sample(&text, r#"heist_refused_total{stage="message",reason="too_fast"}"#), Some(1.0), "{text}");
        assert_eq!(sample(&text, "heist_tick_seconds_count"), Some(1.0), "{text}");
        assert_eq!(sample(&text, "heist_tick_cpu_seconds_total"), Some(0.0015), "{text}");
        for name in ["heist_players", "heist_resumes_total", "heist_received_bytes_total", "heist_draining"] {
            assert!(sample(&text, name).is_some(), "{name} in {text}");
        }
        assert!(text.contains("# HELP heist_players Players connected"), "{text}");
        assert!(text.ends_with("# EOF\n"), "{text}");
    }
}
