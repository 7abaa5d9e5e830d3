//! The Phantom Heist server: an authoritative, headless Bevy app.
//!
//! [`build_server`] makes a ready-to-run [`App`] (and, in secure mode, the token endpoint) so the
//! binary, the demo and the end-to-end tests all start the same server in-process.
#![warn(missing_docs)]

#[cfg(feature = "bots")]
pub mod demo;
pub mod embedded;
pub mod fleet;
pub mod game;
#[cfg(feature = "bots")]
pub mod load;
pub mod net;
pub mod session;
mod tick_grid;

use std::net::SocketAddr;
use std::time::Duration;

use anyhow::Context as _;
use bevy::prelude::*;
use bevy::state::app::StatesPlugin;
use bevy::time::TimeUpdateStrategy;
use bevy_replicon::prelude::*;
use bevy_replicon_renet::RepliconRenetPlugins;
use heist_shared::level::Level;
use heist_shared::protocol::{ProtocolPlugin, TICK_HZ};

use fleet::{Fleet, FleetPlugin};
use game::{Game, GameOptions};
use heist_transport::IntakeLimits;
use net::registry::Registry;
use net::tokens::{CodeBook, JoinCode, TokenConfig, TokenLimits, TokenService};
use net::{Auth, NetSettings, NewSessions, ServerNetPlugin};
use session::{HostSession, LogEcho, Session, SessionPlugin};

/// How the server's clock advances.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clock {
    /// Wall-clock time: [`HostedServer::run`] updates every shard once a tick, on the wall clock.
    RealTime,
    /// Each `app.update()` advances exactly one tick (tests, the demo).
    Stepped,
}

/// Everything needed to start a server.
#[derive(Clone)]
pub struct ServerOptions {
    /// The level to play.
    pub level: Level,
    /// Seed and overrides of the host's session; sessions created on request share the overrides and
    /// draw their own seeds.
    pub game: GameOptions,
    /// Open a session at start-up (the host's: `host`, tests, the demo); without one (`serve`) every
    /// session is created on a player's request.
    pub host_session: bool,
    /// Sessions open at once, the host's included (at most [`net::MAX_SESSIONS`]).
    pub max_sessions: usize,
    /// UDP address for the game (port 0 picks a free one).
    pub bind: SocketAddr,
    /// TCP address for the token endpoint (port 0 picks a free one). Ignored when insecure.
    pub token_bind: SocketAddr,
    /// Accept unsigned clients claiming any role (LAN development only).
    pub insecure: bool,
    /// How time advances.
    pub clock: Clock,
    /// Where the session log goes as it is written.
    pub echo_log: LogEcho,
    /// Refused messages tolerated per client before disconnecting it (default 50).
    pub abuse_limit: u32,
    /// The game address clients are told to use when it differs from the bound one (a relay, a NAT);
    /// `None` advertises the bound address.
    pub advertise: Option<SocketAddr>,
    /// How long a join code works (default 30 min); the host can rotate it sooner.
    pub code_ttl: Duration,
    /// The token endpoint's limits.
    pub token_limits: TokenLimits,
    /// The game socket's limits.
    pub intake_limits: IntakeLimits,
    /// How long a drain waits for running heists ([`fleet::drain`]).
    pub drain_limit: Duration,
    /// How long without an update the game loop counts as stalled (health, Agones).
    pub stall_after: Duration,
    /// Sessions one shard plays at most: a shard is a replication server (a Bevy app with its own
    /// replicon, renet and game UDP port) for its sessions alone, so the cost of a session's tick does
    /// not grow with the sessions other shards play (docs/decisions.md). A server of `max_sessions` runs
    /// `max_sessions.div_ceil(shard_size)` shards, all ticked by one game loop.
    pub shard_size: usize,
    /// The shards' game ports, one each, when they are not consecutive (Agones gives each its own);
    /// empty: shard `i` binds `bind`'s port + `i` (every one port 0 when `bind`'s is 0), and is
    /// advertised at `advertise`'s port + `i`.
    pub ports: Vec<u16>,
}

/// Sessions a shard plays unless told otherwise (the load figures in docs/performance.md).
pub const DEFAULT_SHARD_SIZE: usize = 8;

/// How long a join code works unless the host says otherwise.
pub const DEFAULT_CODE_TTL: Duration = Duration::from_secs(30 * 60);

impl ServerOptions {
    /// Loopback, secure, stepped clock, the shipped museum.
    pub fn local_test(seed: u64) -> Self {
        let loopback: SocketAddr = "127.0.0.1:0".parse().unwrap_or_else(|_| unreachable!());
        Self {
            level: Level::museum(),
            game: GameOptions { seed, ..Default::default() },
            host_session: true,
            max_sessions: 1,
            bind: loopback,
            token_bind: loopback,
            insecure: false,
            clock: Clock::Stepped,
            echo_log: LogEcho::Off,
            abuse_limit: 50,
            advertise: None,
            code_ttl: DEFAULT_CODE_TTL,
            token_limits: TokenLimits::default(),
            intake_limits: IntakeLimits::default(),
            drain_limit: fleet::DEFAULT_DRAIN_LIMIT,
            stall_after: fleet::STALL_AFTER,
            shard_size: DEFAULT_SHARD_SIZE,
            ports: Vec::new(),
        }
    }

    /// Shard `i`'s bound address and the address its players are told.
    fn shard_addrs(&self, i: usize) -> anyhow::Result<(SocketAddr, Option<SocketAddr>)> {
        let port = |base: u16| -> anyhow::Result<u16> {
            match self.ports.get(i) {
                Some(p) => Ok(*p),
                None if !self.ports.is_empty() => anyhow::bail!("{} game ports for {} shards", self.ports.len(), i + 1),
                None if base == 0 => Ok(0),
                None => u16::try_from(usize::from(base) + i).context("the shards' game ports run past 65535"),
            }
        };
        let mut bind = self.bind;
        bind.set_port(port(self.bind.port())?);
        let advertise = match self.advertise {
            Some(mut a) => {
                a.set_port(port(a.port())?);
                Some(a)
            }
            None => None,
        };
        Ok((bind, advertise))
    }
}

/// One shard: a replication server for its sessions alone — a Bevy app with its own replicon, renet
/// and game socket — ticked with the others by the server's game loop.
pub struct Shard {
    /// The Bevy app.
    pub app: App,
    /// Its game address, as bound.
    pub addr: SocketAddr,
    /// The game address its players are given in their tokens.
    pub advertised: SocketAddr,
}

/// A built server, not yet running.
pub struct HostedServer {
    /// Its shards (one unless `max_sessions` exceeds `shard_size`); the first plays the host's session.
    pub shards: Vec<Shard>,
    /// The first shard's game address, as bound.
    pub addr: SocketAddr,
    /// The game address the first shard's players are given in their tokens (the bound one unless
    /// advertised otherwise).
    pub advertised: SocketAddr,
    /// The token endpoint (secure mode).
    pub tokens: Option<TokenService>,
    /// The sessions, as the endpoint sees them.
    pub registry: Registry,
    /// The host's session's code book (secure mode, with a host session).
    pub codes: Option<CodeBook>,
    /// Its heartbeat, metrics and drain (also a resource of the app).
    pub fleet: Fleet,
}

impl HostedServer {
    /// One tick of the game loop: every shard's app updates once. (Never inlined: a profile finds the
    /// server's work under it.)
    #[inline(never)]
    pub fn update(&mut self) {
        for shard in &mut self.shards {
            shard.app.update();
        }
    }

    /// The first shard's world (the host's session, when there is one, lives there).
    pub fn world(&self) -> &World {
        self.shards[0].app.world()
    }

    /// The first shard's world, to change.
    pub fn world_mut(&mut self) -> &mut World {
        self.shards[0].app.world_mut()
    }

    /// How the game loop ended, once every shard has exited: the first error, else success.
    pub fn should_exit(&self) -> Option<AppExit> {
        let exits: Option<Vec<AppExit>> = self.shards.iter().map(|s| s.app.should_exit()).collect();
        exits.map(|exits| exits.into_iter().find(AppExit::is_error).unwrap_or(AppExit::Success))
    }

    /// Runs the game loop in real time until every shard has exited (a drain, a failure): each shard
    /// updates once a game tick, in turn, on a grid of deadlines 1/60 s apart, and its clock reads the
    /// deadline, so each update runs exactly one fixed step; a loop that falls behind updates at the
    /// latest deadline past, and the fixed schedule runs every step it missed. A shard that has exited is
    /// no longer updated.
    pub fn run(&mut self) -> AppExit {
        // Every shard steps at the same fixed rate (`shard_app`): the grid is that step.
        let step = self.shards[0].app.world().resource::<Time<Fixed>>().timestep();
        let mut grid = tick_grid::TickGrid::new(std::time::Instant::now(), step);
        loop {
            let deadline = grid.next(std::time::Instant::now());
            if let Some(rest) = deadline.checked_duration_since(std::time::Instant::now()) {
                std::thread::sleep(rest);
            }
            for shard in &mut self.shards {
                if shard.app.should_exit().is_none() {
                    shard.app.insert_resource(TimeUpdateStrategy::ManualInstant(deadline));
                    shard.app.update();
                }
            }
            if let Some(exit) = self.should_exit() {
                return exit;
            }
        }
    }

    /// The host's session (the one opened at start-up).
    ///
    /// # Panics
    /// When the server was built without one ([`ServerOptions::host_session`] false): a test's mistake.
    pub fn host_session(&self) -> &Session {
        let world = self.world();
        world
            .resource::<HostSession>()
            .0
            .and_then(|e| world.get::<Session>(e))
            .expect("the server was built with a host session")
    }

    /// The host's session's game state (see [`HostedServer::host_session`]).
    pub fn game(&self) -> &Game {
        &self.host_session().game
    }

    /// The host's session's join code in force (secure mode).
    pub fn join_code(&self) -> Option<JoinCode> {
        self.codes.as_ref().map(CodeBook::current)
    }

    /// The host's session's log so far.
    pub fn log(&self) -> &[String] {
        &self.host_session().log.lines
    }

    /// Every session being played, in no particular order.
    pub fn sessions(&mut self) -> Vec<&Session> {
        let mut all = Vec::new();
        for shard in &mut self.shards {
            let world = shard.app.world_mut();
            let mut query = world.query::<&Session>();
            // The query state only borrows the world; its items live as long as the world's borrow.
            let world: &World = world;
            all.extend(query.iter(world));
        }
        all
    }
}

/// Builds the server's shards, binds their sockets and starts the token endpoint.
pub fn build_server(options: ServerOptions) -> anyhow::Result<HostedServer> {
    let max_sessions = options.max_sessions.clamp(1, net::MAX_SESSIONS);
    let shard_size = options.shard_size.clamp(1, max_sessions);
    let shard_count = max_sessions.div_ceil(shard_size);
    let mut sockets = Vec::with_capacity(shard_count);
    for i in 0..shard_count {
        let (bind, advertise) = options.shard_addrs(i)?;
        let socket = net::bind_game_socket(bind).with_context(|| format!("cannot bind UDP {bind}"))?;
        let addr = socket.local_addr()?;
        let advertise = match advertise {
            None if addr.ip().is_unspecified() => Some(net::advertise_for(addr)?),
            a => a,
        };
        sockets.push((socket, addr, advertise));
    }
    let registry = Registry::sharded(max_sessions, shard_size, options.code_ttl, options.token_limits.creates);
    let fleet = Fleet::new(max_sessions, options.drain_limit, options.stall_after);
    let host_entry = if options.host_session {
        let entry = registry.open(None).map_err(|e| anyhow::anyhow!("cannot open the host's session: {e}"))?;
        registry.take_opened(entry.shard); // spawned below, with the host's options
        Some(entry)
    } else {
        None
    };
    let (auth, tokens) = if options.insecure {
        (Auth::Insecure, None)
    } else {
        let private_key: [u8; 32] = rand::random();
        let service = TokenService::spawn(
            options.token_bind,
            TokenConfig {
                registry: registry.clone(),
                private_key,
                server_addrs: sockets.iter().map(|(_, addr, advertise)| advertise.unwrap_or(*addr)).collect(),
                limits: options.token_limits,
                metrics: fleet.metrics.clone(),
            },
        )
        .with_context(|| format!("cannot bind the token endpoint on TCP {}", options.token_bind))?;
        (Auth::Secure { private_key }, Some(service))
    };
    let codes = host_entry.as_ref().filter(|_| !options.insecure).map(|e| e.codes.clone());
    let new_sessions = NewSessions { level: options.level.clone(), game: options.game.clone(), echo: options.echo_log };

    let mut shards = Vec::with_capacity(shard_count);
    for (shard, (socket, addr, advertise)) in sockets.into_iter().enumerate() {
        let settings = NetSettings {
            auth: auth.clone(),
            registry: registry.clone(),
            shard,
            abuse_limit: options.abuse_limit,
            advertise,
            new_sessions: new_sessions.clone(),
            metrics: fleet.metrics.clone(),
        };
        let mut app = shard_app(options.clock, &fleet, socket, settings, options.intake_limits);
        if let Some(entry) = host_entry.as_ref().filter(|e| e.shard == shard) {
            let mut session = new_sessions.session(entry, Some(&options.game));
            session.log.record(0.0, session::Record::SessionCreated, "session created; waiting for players".into());
            let world = app.world_mut();
            let entity = session::spawn_session(&mut world.commands(), session);
            world.flush();
            world.insert_resource(HostSession(Some(entity)));
        }
        app.finish();
        app.cleanup();
        shards.push(Shard { app, addr, advertised: advertise.unwrap_or(addr) });
    }
    let (addr, advertised) = (shards[0].addr, shards[0].advertised);
    Ok(HostedServer { shards, addr, advertised, tokens, registry, codes, fleet })
}

/// Replicon's plugins without its client side: the crate is built with replicon's `client` feature (the
/// bots and the clients' embedded host share it), but a shard is only a server, and each of its systems
/// costs every tick (most when the caches are cold: tens of shards' apps run in turn).
fn server_replicon() -> bevy::app::PluginGroupBuilder {
    RepliconPlugins
        .build()
        .disable::<bevy_replicon::client::ClientPlugin>()
        .disable::<bevy_replicon::client::message::ClientMessagePlugin>()
}

/// Renet's replicon backend without its client side (as [`server_replicon`]).
fn server_renet() -> bevy::app::PluginGroupBuilder {
    RepliconRenetPlugins.build().disable::<bevy_replicon_renet::RepliconRenetClientPlugin>()
}

/// One shard's app: replicon and renet on `socket`, the sessions `settings.shard` plays, the fleet side.
fn shard_app(
    clock: Clock,
    fleet: &Fleet,
    socket: std::net::UdpSocket,
    settings: NetSettings,
    intake: IntakeLimits,
) -> App {
    let mut app = App::new();
    app.add_plugins(MinimalPlugins);
    if clock == Clock::Stepped {
        let period = Duration::from_secs_f64(1.0 / TICK_HZ);
        app.insert_resource(TimeUpdateStrategy::ManualDuration(period));
    }
    app.insert_resource(Time::<Fixed>::from_hz(TICK_HZ))
        .add_plugins((StatesPlugin, server_replicon(), server_renet(), ProtocolPlugin))
        .add_plugins(SessionPlugin)
        .insert_resource(fleet.clone())
        .add_plugins(FleetPlugin)
        .add_plugins(ServerNetPlugin { socket: std::sync::Mutex::new(Some(socket)), settings, intake });
    app
}
