//! Running on a fleet (docs/deploy.md): what an orchestrator needs of the server.
//!
//! Always present in a built server ([`Fleet`], [`FleetPlugin`]): the heartbeat every update stamps,
//! the metrics every part counts into, the drain request and its handling in the game loop. Started on
//! demand ([`FleetServices::start`]): the health and metrics endpoint (`--metrics`), the Agones link
//! (`--agones`) and the termination signals (the binary's `serve` and `host`).

pub mod agones;
pub mod drain;
pub mod health;
pub mod http;
pub mod metrics;
pub mod signals;

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bevy::prelude::*;

use crate::net::NetSettings;
use crate::net::transport::{GameTransport, Traffic};
use crate::session::Session;
pub use drain::{DEFAULT_DRAIN_LIMIT, Drain};
use drain::{DrainProgress, drain_sessions};
pub use health::{Heartbeat, STALL_AFTER};
pub use metrics::Metrics;

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

/// Stamps the heartbeat, times each update, keeps the gauges and counters, carries out a drain.
pub struct FleetPlugin;

impl Plugin for FleetPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<DrainProgress>()
            .init_resource::<UpdateStart>()
            .add_systems(First, start_update)
            .add_systems(Update, (drain_sessions, exit_on_failure))
            .add_systems(Last, end_update);
    }
}

#[derive(Resource)]
struct UpdateStart(Instant);

impl Default for UpdateStart {
    fn default() -> Self {
        Self(Instant::now())
    }
}

fn start_update(mut start: ResMut<UpdateStart>) {
    start.0 = Instant::now();
}

fn exit_on_failure(fleet: Res<Fleet>, mut exit: MessageWriter<AppExit>) {
    if fleet.failure().is_some() {
        exit.write(AppExit::error());
    }
}

/// Observes the update's time, beats, and brings the gauges and counters up to date.
#[allow(clippy::too_many_arguments)]
fn end_update(
    start: Res<UpdateStart>,
    fleet: Res<Fleet>,
    settings: Res<NetSettings>,
    sessions: Query<&Session>,
    added: Query<(), Added<Session>>,
    mut removed: RemovedComponents<Session>,
    transport: Option<Res<GameTransport>>,
    mut counted: Local<Traffic>,
    mut seated: Local<(i64, i64)>,
) {
    let m = &fleet.metrics;
    m.tick_seconds.observe(start.0.elapsed().as_secs_f64());
    fleet.heartbeat.beat();
    m.sessions.set(settings.registry.len() as i64);
    m.sessions_created.inc_by(added.iter().count() as u64);
    m.sessions_ended.inc_by(removed.read().count() as u64);
    let (mut players, mut kept) = (0, 0);
    for session in &sessions {
        players += i64::from(session.roles.vive.is_some()) + i64::from(session.roles.phantom.is_some());
        kept += session.game.kept_seats() as i64;
    }
    // Every shard counts its own into the shared gauges: each adds what changed since it last did.
    m.players.inc_by(players - seated.0);
    m.seats_kept.inc_by(kept - seated.1);
    *seated = (players, kept);
    if let Some(traffic) = transport.map(|t| t.traffic()) {
        m.bytes_received.inc_by(traffic.received.saturating_sub(counted.received));
        m.bytes_sent.inc_by(traffic.sent.saturating_sub(counted.sent));
        *counted = traffic;
    }
}

/// Which fleet services to start beside the game loop.
#[derive(Clone, Debug, Default)]
pub struct FleetOptions {
    /// Serve `/healthz` and `/metrics` on this TCP address.
    pub metrics: Option<SocketAddr>,
    /// Report to the Agones sidecar.
    pub agones: Option<agones::AgonesOptions>,
}

/// The running fleet services of a server.
pub struct FleetServices {
    /// The health and metrics endpoint.
    pub http: Option<http::MetricsServer>,
    /// The Agones link.
    pub agones: Option<agones::AgonesLink>,
}

impl FleetServices {
    /// Starts what `options` asks for, on threads of their own, for `server` (its sockets are bound:
    /// Agones is told Ready).
    pub fn start(server: &crate::HostedServer, options: &FleetOptions) -> anyhow::Result<Self> {
        use anyhow::Context as _;
        let http = match options.metrics {
            Some(bind) => Some(
                http::MetricsServer::spawn(bind, server.fleet.clone())
                    .with_context(|| format!("cannot serve metrics on TCP {bind}"))?,
            ),
            None => None,
        };
        let agones = match &options.agones {
            Some(o) => {
                let info = agones::GameServerInfo { registry: server.registry.clone(), advertised: server.advertised };
                Some(agones::AgonesLink::spawn(o.clone(), server.fleet.clone(), info)?)
            }
            None => None,
        };
        Ok(Self { http, agones })
    }

    /// After the game loop ended: tells Agones `Shutdown` (if linked) and stops the endpoint.
    pub fn shut_down(self) {
        if let Some(link) = self.agones {
            link.shut_down();
        }
        drop(self.http);
    }
}
