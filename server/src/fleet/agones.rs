//! `serve --agones`: the server as an Agones game server, through the official `agones` crate.
//!
//! The SDK's async client runs on a thread of its own (a current-thread tokio runtime); the game loop
//! never waits on it. It reads what it reports from shared state: the heartbeat (health pings stop when
//! the loop stalls, so Agones restarts the pod), the session registry (the `sessions` Counter, the
//! `players` List of seated players' public seat ids) and the drain request.

use bevy::log::{error, info, warn};
use std::collections::BTreeSet;
use std::net::SocketAddr;
use std::thread::JoinHandle;
use std::time::Duration;

use heist_shared::protocol::join::JOIN_VERSION;

use super::Fleet;
use crate::net::registry::Registry;

/// The Counter the fleet's GameServer spec declares for sessions (deploy/fleet.yaml).
pub const SESSIONS_COUNTER: &str = "sessions";
/// The List it declares for players.
pub const PLAYERS_LIST: &str = "players";
/// The annotation carrying the address players are given (Kubernetes label values cannot hold a port).
pub const ADDRESS_ANNOTATION: &str = "phantom-heist.address";
/// The label carrying the join protocol version (a client of another version cannot join).
pub const VERSION_LABEL: &str = "phantom-heist.join-version";
/// The name of the GameServer port the server plays on (UDP game and TCP tokens, deploy/fleet.yaml; a
/// `TCPUDP` port appears in the status as `game-udp` and `game-tcp`).
pub const GAME_PORT: &str = "game";

/// The GameServer port shard `shard` serves on: [`GAME_PORT`] for the first, `game-1`, `game-2`, ... after.
pub fn game_port_name(shard: usize) -> String {
    if shard == 0 { GAME_PORT.to_owned() } else { format!("{GAME_PORT}-{shard}") }
}

/// How the link to the sidecar behaves.
#[derive(Clone, Debug)]
pub struct AgonesOptions {
    /// The SDK server's gRPC port on localhost; `None`: `$AGONES_SDK_GRPC_PORT`, else 9357.
    pub port: Option<u16>,
    /// Time between health pings (Agones' default check period is 5 s; pinging faster is harmless).
    pub health_every: Duration,
    /// Time between looks at the sessions and players.
    pub sync_every: Duration,
}

impl Default for AgonesOptions {
    fn default() -> Self {
        Self { port: None, health_every: Duration::from_secs(1), sync_every: Duration::from_millis(250) }
    }
}

/// What the link needs of the server.
pub struct GameServerInfo {
    /// The sessions.
    pub registry: Registry,
    /// The address players reach it at.
    pub advertised: SocketAddr,
}

/// A running link to the Agones sidecar.
pub struct AgonesLink {
    finish: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl AgonesLink {
    /// Connects on a thread of its own and reports from then on; a failure to reach the sidecar is
    /// fatal to the server ([`Fleet::fatal`]).
    pub fn spawn(options: AgonesOptions, fleet: Fleet, info: GameServerInfo) -> std::io::Result<Self> {
        let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
        let (finish, finished) = tokio::sync::oneshot::channel();
        let thread = std::thread::Builder::new().name("agones".into()).spawn(move || {
            runtime.block_on(async move {
                if let Err(e) = run(options, fleet.clone(), info, finished).await {
                    error!("Agones: {e}");
                    fleet.fail(format!("Agones: {e}"));
                }
            });
        })?;
        Ok(Self { finish: Some(finish), thread: Some(thread) })
    }

    /// After the game loop ended (a drain, usually): tells Agones `Shutdown` and waits for the thread.
    pub fn shut_down(mut self) {
        if let Some(finish) = self.finish.take() {
            let _ = finish.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The SDK server's port: `port`, else `$AGONES_SDK_GRPC_PORT`, else Agones' default 9357.
fn sdk_port(port: Option<u16>) -> u16 {
    port.unwrap_or_else(|| std::env::var("AGONES_SDK_GRPC_PORT").ok().and_then(|p| p.parse().ok()).unwrap_or(9357))
}

/// Where Agones says players reach this game server: its `status.address` and the host port of its
/// `port_name` port (`None` when the GameServer has no such port: the caller keeps its own). Asked
/// before the sockets are bound (a `Passthrough` port is only known then); blocks up to the SDK's
/// 30 s connection timeout.
pub fn public_address(options: &AgonesOptions, port_name: &str) -> anyhow::Result<(std::net::IpAddr, Option<u16>)> {
    let (ip, ports) = public_ports(options, &[port_name.to_owned()])?;
    Ok((ip, ports.into_iter().next().flatten()))
}

/// As [`public_address`], for several ports at once (one a shard: [`game_port_name`]).
pub fn public_ports(
    options: &AgonesOptions,
    port_names: &[String],
) -> anyhow::Result<(std::net::IpAddr, Vec<Option<u16>>)> {
    let port = sdk_port(options.port);
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
    runtime.block_on(async {
        let mut sdk = agones::Sdk::new(Some(port), None).await.map_err(|e| {
            anyhow::anyhow!("cannot reach the Agones SDK server at localhost:{port} (is the sidecar running?): {e}")
        })?;
        let gs = call("GetGameServer", sdk.get_gameserver()).await.map_err(anyhow::Error::msg)?;
        let status = gs.status.unwrap_or_default();
        let ip = status.address.parse().map_err(|e| {
            anyhow::anyhow!("Agones gives the game server the address {:?}, not an IP address ({e})", status.address)
        })?;
        // A TCPUDP port shows as two of one number, `NAME-udp` and `NAME-tcp` (Agones' port allocator).
        let host_port = |port_name: &String| {
            let names = [port_name.clone(), format!("{port_name}-udp"), format!("{port_name}-tcp")];
            names
                .iter()
                .find_map(|name| status.ports.iter().find(|p| p.name == *name))
                .and_then(|p| u16::try_from(p.port).ok())
        };
        Ok((ip, port_names.iter().map(host_port).collect()))
    })
}

/// Bounds every call, so a hung sidecar cannot hold the link (or the shutdown) forever.
async fn call<T>(what: &str, f: impl std::future::Future<Output = agones::errors::Result<T>>) -> Result<T, String> {
    match tokio::time::timeout(Duration::from_secs(5), f).await {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(format!("{what} failed: {e}")),
        Err(_) => Err(format!("{what} got no answer within 5 s")),
    }
}

async fn run(
    options: AgonesOptions,
    fleet: Fleet,
    info: GameServerInfo,
    mut finished: tokio::sync::oneshot::Receiver<()>,
) -> Result<(), String> {
    let port = sdk_port(options.port);
    let mut sdk = agones::Sdk::new(Some(port), None)
        .await
        .map_err(|e| format!("cannot reach the SDK server at localhost:{port} (is the sidecar running?): {e}"))?;
    call("Ready", sdk.ready()).await?;
    info!("Agones: Ready (SDK server at localhost:{port})");
    for (what, result) in [
        (
            "SetAnnotation",
            call("SetAnnotation", sdk.set_annotation(ADDRESS_ANNOTATION, info.advertised.to_string())).await,
        ),
        ("SetLabel", call("SetLabel", sdk.set_label(VERSION_LABEL, JOIN_VERSION.to_string())).await),
    ] {
        if let Err(e) = result {
            warn!("Agones: {what}: {e}");
        }
    }
    let max = info.registry.max() as i64;
    let mut beta = sdk.beta().clone();
    if let Err(e) = call("capacity", beta.set_counter_capacity(SESSIONS_COUNTER, max)).await {
        warn!("Agones: the `{SESSIONS_COUNTER}` Counter ({e}): declare it in the GameServer spec");
    }
    if let Err(e) = call("capacity", beta.set_list_capacity(PLAYERS_LIST, (2 * max).min(1000))).await {
        warn!("Agones: the `{PLAYERS_LIST}` List ({e}): declare it in the GameServer spec");
    }
    tokio::spawn(ping_health(sdk.health_check(), fleet.clone(), options.health_every));
    tokio::spawn(watch(sdk.clone(), fleet.clone()));

    let mut synced = Synced { capacity: max, ..Synced::default() };
    let mut every = tokio::time::interval(options.sync_every);
    every.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tokio::select! {
            _ = &mut finished => break,
            _ = every.tick() => synced.sync(&mut beta, &info.registry).await,
        }
    }
    synced.sync(&mut beta, &info.registry).await;
    call("Shutdown", sdk.shutdown()).await?;
    info!("Agones: Shutdown");
    Ok(())
}

/// Pings while the game loop is alive; stops (and says so once) while it is stalled.
async fn ping_health(health: tokio::sync::mpsc::Sender<()>, fleet: Fleet, every: Duration) {
    let mut tick = tokio::time::interval(every);
    let mut was_stalled = false;
    loop {
        tick.tick().await;
        let stalled = fleet.heartbeat.stalled(fleet.stall_after);
        if stalled != was_stalled {
            if stalled {
                error!(
                    "the game loop stalled (no update for {:.1} s): health pings stop, Agones will restart the server",
                    fleet.heartbeat.age().unwrap_or_default().as_secs_f64()
                );
            } else {
                warn!("the game loop runs again: health pings resume");
            }
            was_stalled = stalled;
        }
        if !stalled && health.try_send(()).is_err() && health.is_closed() {
            error!("Agones: the health stream closed");
            return;
        }
    }
}

/// Logs the game server's state as Agones changes it (an allocation above all); a `Shutdown` state
/// starts a drain.
async fn watch(mut sdk: agones::Sdk, fleet: Fleet) {
    let mut stream = match call("WatchGameServer", sdk.watch_gameserver()).await {
        Ok(s) => s,
        Err(e) => return warn!("Agones: {e}"),
    };
    let mut last = String::new();
    while let Ok(Some(gs)) = stream.message().await {
        let state = gs.status.map(|s| s.state).unwrap_or_default();
        if state == last {
            continue;
        }
        match state.as_str() {
            "Allocated" => info!(target: "fleet", event = "allocated", "Agones: the game server is Allocated"),
            "Shutdown" if fleet.drain.request() => info!("Agones: the game server is Shutdown: draining"),
            s => info!("Agones: the game server is {s}"),
        }
        last = state;
    }
}

/// What the sidecar was last told.
#[derive(Default)]
struct Synced {
    sessions: i64,
    capacity: i64,
    players: BTreeSet<String>,
}

impl Synced {
    /// Brings the `sessions` Counter and the `players` List up to date. While draining, the Counter's
    /// capacity follows its count down, so no allocation picks this server.
    async fn sync(&mut self, beta: &mut agones::beta::Beta, registry: &Registry) {
        let sessions = registry.len() as i64;
        if sessions != self.sessions {
            match call("UpdateCounter", beta.set_counter_count(SESSIONS_COUNTER, sessions)).await {
                Ok(()) => self.sessions = sessions,
                Err(e) => warn!("Agones: {e}"),
            }
        }
        if registry.is_draining() && self.capacity != self.sessions {
            match call("UpdateCounter", beta.set_counter_capacity(SESSIONS_COUNTER, self.sessions)).await {
                Ok(()) => self.capacity = self.sessions,
                Err(e) => warn!("Agones: {e}"),
            }
        }
        let now: BTreeSet<String> = registry.seated_players().into_iter().collect();
        for gone in self.players.difference(&now).cloned().collect::<Vec<_>>() {
            match call("RemoveListValue", beta.delete_list_value(PLAYERS_LIST, &gone)).await {
                Ok(()) => {
                    self.players.remove(&gone);
                }
                Err(e) => warn!("Agones: {e}"),
            }
        }
        for new in now.difference(&self.players).cloned().collect::<Vec<_>>() {
            match call("AddListValue", beta.append_list_value(PLAYERS_LIST, &new)).await {
                Ok(()) => {
                    self.players.insert(new);
                }
                Err(e) => warn!("Agones: {e}"),
            }
        }
    }
}
