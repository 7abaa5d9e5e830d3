//! `heist-server load`: many bot pairs against one server process over loopback UDP, each pair in a
//! session of its own that it created through the token endpoint, and what it costs the server.
//!
//! Everything is stepped in lockstep on one thread (the server — every shard — then every client, once a
//! tick), so the server's cost per tick is its own thread's CPU time for that update, undisturbed by the
//! bots (a profile tells the server's work by [`HostedServer::update`] in its stacks); time
//! is game time (a tick is 1/60 s), so bytes per second are per second of play whatever the machine's
//! speed. Every bot pair asks for another round after each result, so the load is steady.

use std::time::Duration;

use anyhow::Context as _;
use bevy::prelude::*;
use heist_bots::ViveStyle;
use heist_shared::protocol::TICK_HZ;
use heist_transport::IntakeLimits;
use heist_transport::limit::Rate;

use crate::fleet::thread_cpu;
use crate::net::admission_count;
use crate::net::registry::CreateLimits;
use crate::net::transport::GameTransport;
use crate::{HostedServer, ServerOptions, build_server};

mod churn;
mod pairs;
pub use churn::{AWAY_S, ChurnCounts, MAX_LEAD_S};
pub use pairs::{create_bot_pair, create_bot_pair_at};

/// How a load run goes.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Sessions, each with a Vive bot and a Phantom bot.
    pub sessions: usize,
    /// Seconds of game time measured (after every client is in).
    pub seconds: f32,
    /// How the Vive bots play.
    pub style: ViveStyle,
    /// Serve `/healthz` and `/metrics` here while the load runs.
    pub metrics: Option<std::net::SocketAddr>,
    /// Sessions a shard plays at most.
    pub shard_size: usize,
    /// What tells the server's own heap apart from the bots' (the binary's counting allocator).
    pub heap: Option<HeapProbe>,
    /// Players come and go: every this many seconds of game time each session loses a player who comes
    /// back with the seat's ticket, or both leave and a new pair creates a session ([`churn`]).
    pub churn: Option<f32>,
    /// Evict the caches before every measured server tick by writing this many MB (more than the
    /// machine's last-level cache), so that every run, whatever the bots' own memory, measures the
    /// server from the same cold cache ([`Evictor`]).
    pub cold_cache_mb: Option<u32>,
}

/// Writes a buffer larger than the last-level cache, a byte in every 64-byte line, so that the next server
/// tick finds none of its data cached: the state a 300-session run's bots (about 1.2 GB of apps updated
/// between two server ticks) leave the cache in, given to a run of any size.
pub struct Evictor {
    buffer: Vec<u8>,
    round: u8,
}

impl Evictor {
    /// A buffer of `mb` MB (at most [`Evictor::MAX_MB`]), zeroed here so that its pages are resident
    /// before the measurement; an error if it is too big or the memory cannot be had.
    pub fn new(mb: u32) -> anyhow::Result<Self> {
        anyhow::ensure!((1..=Self::MAX_MB).contains(&mb), "--cold-cache {mb} MB is outside 1..={} MB", Self::MAX_MB);
        let bytes = (mb as usize) << 20;
        let mut buffer = Vec::new();
        buffer
            .try_reserve_exact(bytes)
            .map_err(|e| anyhow::anyhow!("--cold-cache {mb} MB: cannot allocate its buffer ({e})"))?;
        buffer.resize(bytes, 0);
        Ok(Self { buffer, round: 0 })
    }

    /// The largest buffer, MB: far more than any last-level cache, little enough to write every tick.
    pub const MAX_MB: u32 = 4096;

    /// Writes every cache line of the buffer.
    pub fn evict(&mut self) {
        self.round = self.round.wrapping_add(1);
        for line in self.buffer.chunks_mut(64) {
            line[0] = self.round;
        }
        std::hint::black_box(&self.buffer);
    }
}

/// The net heap bytes allocated while a thread is flagged as doing the server's work: an allocator's
/// view that separates the server's memory from the bots' in one process (`heist-server load` installs
/// one; a library cannot).
#[derive(Clone, Copy, Debug)]
pub struct HeapProbe {
    /// Flags the calling thread as doing the server's work (true) or not.
    pub flag: fn(bool),
    /// Net bytes allocated by flagged work so far.
    pub bytes: fn() -> i64,
}

/// What a load run measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LoadReport {
    /// Sessions played.
    pub sessions: usize,
    /// Shards they were spread over.
    pub shards: usize,
    /// Ticks measured.
    pub ticks: u64,
    /// Server CPU per tick divided by the sessions, µs: median.
    pub session_tick_us_median: f64,
    /// The same, 99th percentile.
    pub session_tick_us_p99: f64,
    /// Server CPU per tick, ms: median.
    pub tick_ms_median: f64,
    /// The same, 99th percentile.
    pub tick_ms_p99: f64,
    /// Wall time of a whole server tick (every shard's update), ms, 99th percentile.
    pub tick_wall_ms_p99: f64,
    /// CPU time of stepping every bot client once between two server ticks, ms, median: the load
    /// generator's own cost, which shares the server's core and last-level cache in this process.
    pub bots_tick_ms_median: f64,
    /// Bytes a second each client sent the server (UDP payloads), averaged over the clients.
    pub client_bytes_per_s_up: f64,
    /// Bytes a second the server sent each client.
    pub client_bytes_per_s_down: f64,
    /// Datagrams a second each client sent the server.
    pub client_datagrams_per_s_up: f64,
    /// Datagrams a second the server sent each client.
    pub client_datagrams_per_s_down: f64,
    /// Players admitted when the measurement began (2 per session when all are in).
    pub players: usize,
    /// Players admitted when it ended (with churn, fewer by those away or being replaced then).
    pub players_at_end: usize,
    /// Rounds begun during the measurement (the bots ask for another after each result).
    pub rematches: u32,
    /// The process's resident size, MB, by seconds of game time into the measurement (every
    /// [`RESIDENT_SAMPLE_S`]; the bots' apps live in the same process).
    pub resident_mb: Vec<(f64, f64)>,
    /// The server's own heap (net bytes allocated during its updates since it started ticking), MB,
    /// sampled as `resident_mb`; empty without a [`HeapProbe`].
    pub server_heap_mb: Vec<(f64, f64)>,
    /// What the churn did (with [`LoadOptions::churn`]).
    pub churn: Option<ChurnCounts>,
    /// MB written between measured ticks to evict the caches ([`LoadOptions::cold_cache_mb`]).
    pub cold_cache_mb: Option<u32>,
}

impl std::fmt::Display for LoadReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} sessions over {} shards, {} players ({} at the end), {} ticks measured ({} rematches)",
            self.sessions, self.shards, self.players, self.players_at_end, self.ticks, self.rematches
        )?;
        let cache = match self.cold_cache_mb {
            Some(mb) => format!(" (each tick from a cold cache: {mb} MB written before it)"),
            None => String::new(),
        };
        writeln!(
            f,
            "server CPU per session-tick{cache}: median {:.1} µs, p99 {:.1} µs",
            self.session_tick_us_median, self.session_tick_us_p99
        )?;
        writeln!(
            f,
            "server tick: CPU median {:.3} ms, p99 {:.3} ms; wall p99 {:.3} ms",
            self.tick_ms_median, self.tick_ms_p99, self.tick_wall_ms_p99
        )?;
        writeln!(f, "the bots between two server ticks: CPU median {:.3} ms", self.bots_tick_ms_median)?;
        writeln!(
            f,
            "per client: up {:.0} B/s in {:.0} datagrams/s, down {:.0} B/s in {:.0} datagrams/s",
            self.client_bytes_per_s_up,
            self.client_datagrams_per_s_up,
            self.client_bytes_per_s_down,
            self.client_datagrams_per_s_down
        )?;
        let resident: Vec<String> = self.resident_mb.iter().map(|(s, mb)| format!("{s:.0} s {mb:.1}")).collect();
        write!(f, "resident MB by game time: {}", resident.join(", "))?;
        if !self.server_heap_mb.is_empty() {
            let heap: Vec<String> = self.server_heap_mb.iter().map(|(s, mb)| format!("{s:.0} s {mb:.2}")).collect();
            write!(f, "\nserver heap MB by game time: {}", heap.join(", "))?;
        }
        if let Some(c) = &self.churn {
            write!(
                f,
                "\nchurn: {} clients dropped, {} seats taken back ({} refused; the server counted {}), {} pairs left, \
                 {} sessions created in their place ({} tries while full)",
                c.drops, c.resumes, c.resumes_refused, c.server_resumes, c.leaves, c.created, c.create_retries
            )?;
        }
        Ok(())
    }
}

/// The server of a load run: loopback, no host session, room for `sessions`, and limits raised for one
/// address that creates every session and opens every connection (the bots all live on loopback).
pub fn load_server_options(sessions: usize) -> ServerOptions {
    let mut options = ServerOptions::local_test(0);
    options.host_session = false;
    options.max_sessions = sessions;
    let plenty = Rate::new(10_000.0, 10_000.0);
    options.token_limits.creates = CreateLimits { each: plenty, all: plenty };
    options.intake_limits = IntakeLimits { requests_per_address: plenty, requests_total: plenty, ..Default::default() };
    options
}

/// The `q` quantile (0..=1) of `values`, sorted in place.
fn quantile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let i = ((values.len() - 1) as f64 * q).round() as usize;
    values[i.min(values.len() - 1)]
}

/// Resident size of this process, MB (0 where `/proc` cannot tell).
pub fn resident_mb() -> f64 {
    let pages = std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1).and_then(|p| p.parse::<f64>().ok()))
        .unwrap_or(0.0);
    // SAFETY: sysconf has no preconditions.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    pages * page.max(0) as f64 / 1e6
}

/// One tick of the server (every shard's update): the CPU time of this thread and the wall time it took.
fn tick(server: &mut HostedServer, heap: Option<HeapProbe>) -> (Duration, Duration) {
    let (cpu, wall) = (thread_cpu(), std::time::Instant::now());
    if let Some(h) = heap {
        (h.flag)(true);
    }
    server.update();
    if let Some(h) = heap {
        (h.flag)(false);
    }
    (thread_cpu().saturating_sub(cpu), wall.elapsed())
}

/// Rounds begun after a session's first, counted by looking at every session's round once a second of
/// game time: often enough that no session closes between a rematch and the next look (a round under way
/// outlives its players by the heist's abandon grace, 20 s, or a lobby's idle time).
#[derive(Default)]
struct Rematches {
    /// Each session's round when last looked at.
    seen: std::collections::HashMap<u64, u32>,
    rematches: u32,
}

impl Rematches {
    fn count(&mut self, server: &mut HostedServer) {
        let now: std::collections::HashMap<u64, u32> = server.sessions().iter().map(|s| (s.id, s.game.round)).collect();
        for (id, round) in &now {
            let was = self.seen.get(id).copied().unwrap_or(1);
            self.rematches += round.saturating_sub(was);
        }
        self.seen = now;
    }
}

/// Players admitted by every shard.
fn admitted(server: &mut HostedServer) -> usize {
    server.shards.iter_mut().map(|s| admission_count(s.app.world_mut())).sum()
}

/// Bytes through every shard's game socket.
fn traffic(server: &mut HostedServer) -> crate::net::transport::Traffic {
    let mut all = crate::net::transport::Traffic::default();
    for shard in &server.shards {
        if let Some(t) = shard.app.world().get_resource::<GameTransport>().map(GameTransport::traffic) {
            all.received += t.received;
            all.sent += t.sent;
            all.datagrams_received += t.datagrams_received;
            all.datagrams_sent += t.datagrams_sent;
        }
    }
    all
}

/// Runs the load: `progress` hears what is happening (joins, then the measurement).
pub fn run_load(options: &LoadOptions, mut progress: impl FnMut(&str)) -> anyhow::Result<LoadReport> {
    anyhow::ensure!(
        (1..=crate::net::MAX_SESSIONS).contains(&options.sessions),
        "--sessions {} is outside 1..={}",
        options.sessions,
        crate::net::MAX_SESSIONS
    );
    anyhow::ensure!(options.seconds.is_finite() && options.seconds > 0.0, "--seconds must be above zero");
    anyhow::ensure!(
        options.churn.is_none_or(|s| s.is_finite() && f64::from(s) > AWAY_S + 1.0),
        "--churn must be more than {} seconds (a dropped client stays away {AWAY_S} s)",
        AWAY_S + 1.0
    );
    let mut evictor = options.cold_cache_mb.map(Evictor::new).transpose()?;
    let mut server =
        build_server(ServerOptions { shard_size: options.shard_size, ..load_server_options(options.sessions) })?;
    let fleet = crate::fleet::FleetOptions { metrics: options.metrics, agones: None };
    let game =
        crate::fleet::agones::GameServerInfo { registry: server.registry.clone(), advertised: server.advertised };
    let services = crate::fleet::FleetServices::start(&server.fleet, game, &fleet)?;
    if let Some(http) = &services.http {
        progress(&format!("health and metrics on http://{}/healthz and /metrics", http.addr));
    }
    let endpoint = server.tokens.as_ref().context("the server runs without a token endpoint")?.addr;
    let (built, mut setup_ticks) = (std::time::Instant::now(), 0u64);
    let shards = server.shards.len();
    progress(&format!("{} sessions over {shards} shards", options.sessions));
    let mut pairs: Vec<churn::Pair> = Vec::with_capacity(options.sessions);
    let update_all =
        |pairs: &mut Vec<churn::Pair>| pairs.iter_mut().flat_map(churn::Pair::clients).for_each(App::update);
    for n in 0..options.sessions {
        let apps = create_bot_pair_at(endpoint, options.style, u32::MAX, |_| {})
            .with_context(|| format!("bot pair {}", n + 1))?;
        pairs.push(churn::Pair::new(apps));
        // Let the server take each session and its players in before the next.
        for _ in 0..2 {
            tick(&mut server, options.heap);
            update_all(&mut pairs);
            setup_ticks += 1;
        }
    }
    let want = options.sessions * 2;
    progress(&format!("{} sessions created; waiting for {want} players", options.sessions));
    for _ in 0..(20.0 * TICK_HZ) as u64 {
        if admitted(&mut server) >= want {
            break;
        }
        tick(&mut server, options.heap);
        update_all(&mut pairs);
        setup_ticks += 1;
    }
    let players = admitted(&mut server);
    progress(&format!("{players} of {want} players in; measuring {} s of play", options.seconds));
    let before = traffic(&mut server);
    let mut rounds = Rematches::default();
    rounds.count(&mut server);
    rounds.rematches = 0;
    let ticks = (f64::from(options.seconds) * TICK_HZ).ceil() as u64;
    let sample_every = (RESIDENT_SAMPLE_S * TICK_HZ).round() as u64;
    let heap_mb = || options.heap.map(|h| (h.bytes)() as f64 / 1e6);
    let mut resident = vec![(0.0, resident_mb())];
    let mut server_heap: Vec<(f64, f64)> = heap_mb().map(|mb| (0.0, mb)).into_iter().collect();
    let (mut tick_us, mut wall_us) = (Vec::with_capacity(ticks as usize), Vec::with_capacity(ticks as usize));
    let mut bots_us = Vec::with_capacity(ticks as usize);
    let mut churn = options.churn.map(|s| churn::Churn {
        period: ((f64::from(s) * TICK_HZ).round() as u64).max(1),
        endpoint,
        style: options.style,
        counts: ChurnCounts::default(),
    });
    for n in 1..=ticks {
        if let Some(evictor) = evictor.as_mut() {
            evictor.evict();
        }
        let (cpu, wall) = tick(&mut server, options.heap);
        tick_us.push(cpu.as_secs_f64() * 1e6);
        wall_us.push(wall.as_secs_f64() * 1e6);
        let bots = thread_cpu();
        update_all(&mut pairs);
        bots_us.push(thread_cpu().saturating_sub(bots).as_secs_f64() * 1e6);
        if n.is_multiple_of(TICK_HZ as u64) {
            rounds.count(&mut server);
        }
        if let Some(churn) = churn.as_mut() {
            let lead = (setup_ticks + n) as f64 / TICK_HZ - built.elapsed().as_secs_f64();
            if lead > MAX_LEAD_S {
                std::thread::sleep(Duration::from_secs_f64(lead - MAX_LEAD_S));
            }
            let count = pairs.len();
            for (i, pair) in pairs.iter_mut().enumerate() {
                churn.step(pair, i, count, n);
            }
        }
        if n % sample_every == 0 {
            resident.push((n as f64 / TICK_HZ, resident_mb()));
            server_heap.extend(heap_mb().map(|mb| (n as f64 / TICK_HZ, mb)));
        }
    }
    rounds.count(&mut server);
    let after = traffic(&mut server);
    let players_at_end = admitted(&mut server);
    services.shut_down();
    let seconds = ticks as f64 / TICK_HZ;
    let per_client = (players.max(1) as f64) * seconds;
    let sessions = options.sessions as f64;
    let mut per_session: Vec<f64> = tick_us.iter().map(|us| us / sessions).collect();
    Ok(LoadReport {
        sessions: options.sessions,
        shards,
        ticks,
        session_tick_us_median: quantile(&mut per_session, 0.5),
        session_tick_us_p99: quantile(&mut per_session, 0.99),
        tick_ms_median: quantile(&mut tick_us, 0.5) / 1000.0,
        tick_ms_p99: quantile(&mut tick_us, 0.99) / 1000.0,
        tick_wall_ms_p99: quantile(&mut wall_us, 0.99) / 1000.0,
        bots_tick_ms_median: quantile(&mut bots_us, 0.5) / 1000.0,
        client_bytes_per_s_up: (after.received - before.received) as f64 / per_client,
        client_bytes_per_s_down: (after.sent - before.sent) as f64 / per_client,
        client_datagrams_per_s_up: (after.datagrams_received - before.datagrams_received) as f64 / per_client,
        client_datagrams_per_s_down: (after.datagrams_sent - before.datagrams_sent) as f64 / per_client,
        players,
        players_at_end,
        rematches: rounds.rematches,
        resident_mb: resident,
        server_heap_mb: server_heap,
        churn: churn.map(|c| ChurnCounts { server_resumes: server.fleet.metrics.resumes.get(), ..c.counts }),
        cold_cache_mb: options.cold_cache_mb,
    })
}

/// Seconds of game time between two samples of the resident size.
pub const RESIDENT_SAMPLE_S: f64 = 20.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_pick_the_ranked_value() {
        let mut v: Vec<f64> = (1..=100).map(f64::from).collect();
        v.reverse();
        assert_eq!(quantile(&mut v, 0.5), 51.0);
        assert_eq!(quantile(&mut v, 0.99), 99.0);
        assert_eq!(quantile(&mut [], 0.5), 0.0);
    }

    #[test]
    fn an_evictor_writes_every_cache_line_of_its_buffer_each_time() {
        let mut evictor = Evictor::new(1).expect("1 MB");
        assert!(Evictor::new(0).is_err() && Evictor::new(Evictor::MAX_MB + 1).is_err(), "sizes out of range");
        assert_eq!(evictor.buffer.len(), 1 << 20);
        assert!(evictor.buffer.iter().all(|&b| b == 0), "zeroed, every page touched");
        for round in [1u8, 2] {
            evictor.evict();
            let lines: Vec<u8> = evictor.buffer.iter().step_by(64).copied().collect();
            assert_eq!(lines.len(), (1 << 20) / 64);
            assert!(lines.iter().all(|&b| b == round), "every line written in round {round}");
        }
    }

    /// A cold-cache run measures as any other and says so in its report.
    #[test]
    fn a_cold_cache_load_reports_its_eviction() {
        let options = LoadOptions {
            sessions: 1,
            seconds: 1.0,
            style: ViveStyle::Careful,
            metrics: None,
            shard_size: crate::DEFAULT_SHARD_SIZE,
            heap: None,
            churn: None,
            cold_cache_mb: Some(4),
        };
        let report = run_load(&options, |_| {}).expect("the load runs");
        assert_eq!((report.players, report.ticks), (2, 60));
        assert!(report.session_tick_us_median > 0.0, "{report:?}");
        assert_eq!(report.cold_cache_mb, Some(4));
        assert!(report.to_string().contains("cold cache: 4 MB"), "{report}");
    }

    /// Two sessions, an event every 8 s of game time each: both pairs lose Vive, then Phantom (each comes
    /// back 5 s later with its seat ticket), then leave; their sessions close once abandoned and new pairs
    /// create sessions in their place.
    #[test]
    fn a_load_with_churn_drops_resumes_and_replaces_its_players() {
        let options = LoadOptions {
            sessions: 2,
            seconds: 60.0,
            style: ViveStyle::Careful,
            metrics: None,
            shard_size: crate::DEFAULT_SHARD_SIZE,
            heap: None,
            churn: Some(8.0),
            cold_cache_mb: None,
        };
        let report = run_load(&options, |_| {}).expect("the load runs");
        assert_eq!(report.players, 4, "every player was in before the churn began");
        assert!(report.players_at_end >= 2, "the replacements are playing: {report:?}");
        let c = report.churn.expect("the churn's counts");
        assert!(c.drops >= 4, "each pair lost Vive and Phantom once: {c:?}");
        assert_eq!(c.resumes_refused, 0, "every kept seat was given back: {c:?}");
        // (A pair may be away when the run ends.)
        assert!(c.resumes >= 4 && c.resumes + 2 >= c.drops, "the dropped came back: {c:?}");
        assert_eq!(c.server_resumes, u64::from(c.resumes), "the server admitted each as a resume: {c:?}");
        assert_eq!(c.leaves, 2, "both pairs left: {c:?}");
        assert!(c.created >= 1, "a new pair created a session once the server had room: {c:?}");
    }
}
