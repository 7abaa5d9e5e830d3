//! The Phantom Heist server: an authoritative, headless Bevy app.
//!
//! [`build_server`] makes a ready-to-run [`App`] (and, in secure mode, the token endpoint) so the
//! binary, the demo and the end-to-end tests all start the same server in-process.
#![warn(missing_docs)]

pub mod demo;
pub mod embedded;
pub mod fleet;
pub mod game;
pub mod load;
pub mod net;
pub mod session;

use std::net::SocketAddr;
use std::time::Duration;

use anyhow::Context as _;
use bevy::app::ScheduleRunnerPlugin;
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
    /// Wall-clock time; the app runs its own loop (`App::run`).
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
}

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
        }
    }
}

/// A built server, not yet running.
pub struct HostedServer {
    /// The Bevy app.
    pub app: App,
    /// Its game address, as bound.
    pub addr: SocketAddr,
    /// The game address players are given in their tokens (the bound one unless advertised otherwise).
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
    /// The host's session (the one opened at start-up).
    ///
    /// # Panics
    /// When the server was built without one ([`ServerOptions::host_session`] false): a test's mistake.
    pub fn host_session(&self) -> &Session {
        self.app
            .world()
            .resource::<HostSession>()
            .0
            .and_then(|e| self.app.world().get::<Session>(e))
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
        let world = self.app.world_mut();
        let mut query = world.query::<&Session>();
        query.iter(world).collect()
    }
}

/// Builds the server app, binds its sockets and starts the token endpoint.
pub fn build_server(options: ServerOptions) -> anyhow::Result<HostedServer> {
    let socket = net::bind_game_socket(options.bind).with_context(|| format!("cannot bind UDP {}", options.bind))?;
    let addr = socket.local_addr()?;
    let advertise = match options.advertise {
        None if addr.ip().is_unspecified() => Some(net::advertise_for(addr)?),
        a => a,
    };
    let advertised = advertise.unwrap_or(addr);
    let max_sessions = options.max_sessions.clamp(1, net::MAX_SESSIONS);
    let registry = Registry::new(max_sessions, options.code_ttl, options.token_limits.creates);
    let fleet = Fleet::new(max_sessions, options.drain_limit, options.stall_after);
    let host_entry = if options.host_session {
        let entry = registry.open(None).map_err(|e| anyhow::anyhow!("cannot open the host's session: {e}"))?;
        registry.take_opened(); // spawned below, with the host's options
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
                server_addr: advertised,
                limits: options.token_limits,
                metrics: fleet.metrics.clone(),
            },
        )
        .with_context(|| format!("cannot bind the token endpoint on TCP {}", options.token_bind))?;
        (Auth::Secure { private_key }, Some(service))
    };
    let codes = host_entry.as_ref().filter(|_| !options.insecure).map(|e| e.codes.clone());
    let new_sessions = NewSessions { level: options.level.clone(), game: options.game.clone(), echo: options.echo_log };

    let mut app = App::new();
    let period = Duration::from_secs_f64(1.0 / TICK_HZ);
    match options.clock {
        Clock::RealTime => {
            app.add_plugins(MinimalPlugins.set(ScheduleRunnerPlugin::run_loop(period / 2)));
        }
        Clock::Stepped => {
            app.add_plugins(MinimalPlugins).insert_resource(TimeUpdateStrategy::ManualDuration(period));
        }
    }
    app.insert_resource(Time::<Fixed>::from_hz(TICK_HZ))
        .add_plugins((StatesPlugin, RepliconPlugins, RepliconRenetPlugins, ProtocolPlugin))
        .add_plugins(SessionPlugin)
        .insert_resource(fleet.clone())
        .add_plugins(FleetPlugin)
        .add_plugins(ServerNetPlugin {
            socket: std::sync::Mutex::new(Some(socket)),
            settings: NetSettings {
                auth,
                registry: registry.clone(),
                abuse_limit: options.abuse_limit,
                advertise,
                new_sessions: new_sessions.clone(),
                metrics: fleet.metrics.clone(),
            },
            intake: options.intake_limits,
        });
    if let Some(entry) = &host_entry {
        let mut session = new_sessions.session(entry, Some(&options.game));
        session.log.record(0.0, session::Record::SessionCreated, "session created; waiting for players".into());
        let world = app.world_mut();
        let entity = session::spawn_session(&mut world.commands(), session);
        world.flush();
        world.insert_resource(HostSession(Some(entity)));
    }
    if options.clock == Clock::Stepped {
        app.finish();
        app.cleanup();
    }
    Ok(HostedServer { app, addr, advertised, tokens, registry, codes, fleet })
}
