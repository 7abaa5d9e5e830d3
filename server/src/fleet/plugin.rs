//! What the game loop does for the fleet each update: stamps the heartbeat, times the update, keeps the
//! gauges and counters, carries out a drain ([`super::drain`]), and exits when a helper thread failed.

use std::time::{Duration, Instant};

use bevy::prelude::*;

use super::Fleet;
use crate::net::NetSettings;
use crate::net::transport::{GameTransport, Traffic};
use crate::session::Session;

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

/// When the update began: the wall clock and the thread's CPU clock.
#[derive(Resource)]
struct UpdateStart {
    wall: Instant,
    cpu: Duration,
}

impl Default for UpdateStart {
    fn default() -> Self {
        Self { wall: Instant::now(), cpu: thread_cpu() }
    }
}

fn start_update(mut start: ResMut<UpdateStart>) {
    *start = UpdateStart::default();
}

/// CPU time of the calling thread (zero if the clock cannot be read).
pub(crate) fn thread_cpu() -> Duration {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `ts` is a valid, writable timespec; CLOCK_THREAD_CPUTIME_ID needs nothing else.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    if rc != 0 {
        return Duration::ZERO;
    }
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
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
    m.tick_seconds.observe(start.wall.elapsed().as_secs_f64());
    m.tick_cpu_seconds.inc_by(thread_cpu().saturating_sub(start.cpu).as_secs_f64());
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

/// The game loop's side of a drain.
#[derive(Resource, Debug, Default)]
struct DrainProgress {
    started: Option<Instant>,
    cut: bool,
    exited: bool,
}

/// Carries out a requested drain, each tick.
fn drain_sessions(
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
