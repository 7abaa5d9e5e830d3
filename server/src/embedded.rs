//! A server run inside a player's client: `client_haptic host` and `client_vr host` start one on a thread
//! of their own process, with one session and secure tokens, in real time, and join it themselves.
//!
//! You need this module to host from a client. The server's Bevy app is built and run on its thread (a
//! Bevy app stays on the thread that made it); the client gets its addresses and the join code.

use std::net::SocketAddr;
use std::time::Duration;

use anyhow::Context as _;
use heist_shared::level::Level;

use crate::{Clock, DEFAULT_CODE_TTL, ServerOptions, build_server};

/// Where a server started in this process is reached, and its session's code.
#[derive(Clone, Debug)]
pub struct Embedded {
    /// The address told to the partner (the bound one, or `advertise`).
    pub advertised: SocketAddr,
    /// The token endpoint (TCP, the game port).
    pub endpoint: SocketAddr,
    /// The session's join code.
    pub code: String,
}

/// The `host` command's flags, the same in both clients (the `cli` feature).
#[cfg(feature = "cli")]
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct HostFlags {
    /// Where the server listens (UDP game, TCP join endpoint); 0.0.0.0 for players on other machines.
    #[arg(long, default_value = "127.0.0.1:5757")]
    pub bind: SocketAddr,
    /// The address the partner reaches (behind a NAT or relay).
    #[arg(long)]
    pub advertise: Option<SocketAddr>,
    /// Seed of the first round (default: random, so nobody knows which copies are real).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Seconds a heist lasts (default: the museum's 600, scaled by the difficulty).
    #[arg(long)]
    pub time_limit: Option<f32>,
    /// How hard the guards are: easy, normal or hard.
    #[arg(long, default_value_t = heist_shared::rules::Difficulty::Normal)]
    pub difficulty: heist_shared::rules::Difficulty,
    /// Create the session on this running server (`heist-server serve`) instead of hosting one here.
    #[arg(long, conflicts_with_all = ["bind", "advertise", "seed", "time_limit"])]
    pub server: Option<SocketAddr>,
}

#[cfg(feature = "cli")]
impl HostFlags {
    /// The server to start here (when `--server` names none).
    pub fn options(&self) -> HostOptions {
        HostOptions {
            bind: self.bind,
            advertise: self.advertise,
            seed: self.seed,
            time_limit_s: self.time_limit,
            difficulty: self.difficulty,
        }
    }
}

/// What a server started in this process plays, and where.
#[derive(Clone, Copy, Debug)]
pub struct HostOptions {
    /// Where it listens (UDP game, TCP join endpoint).
    pub bind: SocketAddr,
    /// The address told to the partner, when not the bound one.
    pub advertise: Option<SocketAddr>,
    /// The first round's seed (default: random, and random for every later round).
    pub seed: Option<u64>,
    /// Seconds a heist lasts (default: the level's, scaled by the difficulty).
    pub time_limit_s: Option<f32>,
    /// How hard the guards are.
    pub difficulty: heist_shared::rules::Difficulty,
}

/// Starts a one-session server with `host`'s settings on a thread of this process.
pub fn start(host: HostOptions) -> anyhow::Result<Embedded> {
    let HostOptions { bind, advertise, seed, time_limit_s, difficulty } = host;
    let options = ServerOptions {
        level: Level::museum(),
        game: crate::game::GameOptions {
            seed: seed.unwrap_or_else(rand::random),
            random_rounds: seed.is_none(),
            time_limit_s,
            difficulty,
            ..Default::default()
        },
        host_session: true,
        max_sessions: 1,
        bind,
        token_bind: bind,
        insecure: false,
        clock: Clock::RealTime,
        echo_log: crate::session::LogEcho::Tracing,
        abuse_limit: 50,
        advertise,
        code_ttl: DEFAULT_CODE_TTL,
        token_limits: Default::default(),
        intake_limits: Default::default(),
        drain_limit: crate::fleet::DEFAULT_DRAIN_LIMIT,
        stall_after: crate::fleet::STALL_AFTER,
        shard_size: 1,
        ports: Vec::new(),
    };
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new().name("server".into()).spawn(move || match build_server(options) {
        Ok(mut server) => {
            let code = server.join_code().map(|c| c.code);
            let _ = tx.send(Ok((server.advertised, server.tokens.as_ref().map(|t| t.addr), code)));
            server.run();
        }
        Err(e) => {
            let _ = tx.send(Err(e));
        }
    })?;
    let (advertised, endpoint, code) =
        rx.recv_timeout(Duration::from_secs(10)).context("the server did not start within 10 s")??;
    let (endpoint, code) = endpoint.zip(code).context("the server runs without a join endpoint")?;
    Ok(Embedded { advertised, endpoint, code })
}
