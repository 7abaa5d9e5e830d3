//! The servers that run for players: `serve` (many sessions, on a fleet) and `host` (one session, its
//! join code printed).

use std::io::BufRead as _;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context as _;
use clap::Subcommand;
use heist_server::game::GameOptions;
use heist_server::session::LogEcho;
use heist_server::{Clock, ServerOptions, build_server};
use heist_shared::rules::Difficulty;

use crate::{load_level, max_sessions, positive_seconds};

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Serve many sessions: any player may create one (and gets its join code for a partner), up to
    /// --max-sessions at once; each session ends on its own when it is over, the server runs on.
    Serve {
        /// UDP game address; the token endpoint listens on the same port over TCP.
        #[arg(long, default_value = "127.0.0.1:5757")]
        bind: SocketAddr,
        /// The address players reach the server at, put in their tokens (a NAT, a relay).
        #[arg(long)]
        advertise: Option<SocketAddr>,
        /// Sessions open at once.
        #[arg(long, default_value_t = heist_server::net::tokens::DEFAULT_MAX_SESSIONS,
              value_parser = max_sessions)]
        max_sessions: usize,
        /// Sessions a shard plays at most: each shard serves its sessions on a UDP port of its own, the
        /// next after --bind's (and --advertise's) for each shard after the first.
        #[arg(long, default_value_t = heist_server::DEFAULT_SHARD_SIZE, value_parser = max_sessions)]
        shard_size: usize,
        /// Minutes a session's join code works.
        #[arg(long, default_value_t = 30)]
        code_ttl: u64,
        /// Level file (default: the shipped museum).
        #[arg(long)]
        level: Option<PathBuf>,
        /// Seconds a session waits after a result for another round (and outlives its last player)
        /// before it ends.
        #[arg(long, default_value_t = heist_server::game::SESSION_IDLE_S, value_parser = positive_seconds)]
        idle_end: f32,
        /// Override the level's time limit, seconds.
        #[arg(long, value_parser = positive_seconds)]
        time_limit: Option<f32>,
        /// How hard the guards are in the sessions created here: easy, normal or hard.
        #[arg(long, default_value_t = Difficulty::Normal)]
        difficulty: Difficulty,
        #[command(flatten)]
        fleet: FleetArgs,
        /// Run as an Agones game server: Ready, health pings, the `sessions` Counter and `players` List,
        /// Shutdown after a drain (the SDK sidecar at localhost:$AGONES_SDK_GRPC_PORT, default 9357).
        #[arg(long)]
        agones: bool,
    },
    /// Host a session for players: prints the address and the join code.
    Host {
        /// UDP game address; the token endpoint listens on the same port over TCP.
        #[arg(long, default_value = "127.0.0.1:5757")]
        bind: SocketAddr,
        /// The address players reach the server at, put in their tokens (a NAT, a relay). Needed with an
        /// unspecified --bind (0.0.0.0) when no interface with a route is found.
        #[arg(long)]
        advertise: Option<SocketAddr>,
        /// Seed for the copies and the guards (default: random; it decides which copy is real, so it is
        /// only told when the heist ends).
        #[arg(long)]
        seed: Option<u64>,
        /// Minutes a join code works; type `rotate` for a new one sooner.
        #[arg(long, default_value_t = 30)]
        code_ttl: u64,
        /// Level file (default: the shipped museum).
        #[arg(long)]
        level: Option<PathBuf>,
        /// Accept clients without tokens, claiming any role. LAN development only.
        #[arg(long)]
        insecure: bool,
        /// Seconds the session waits after a result for another round (and outlives its last player)
        /// before it ends and the server exits.
        #[arg(long, default_value_t = heist_server::game::SESSION_IDLE_S, value_parser = positive_seconds)]
        idle_end: f32,
        /// Override the level's time limit, seconds.
        #[arg(long, value_parser = positive_seconds)]
        time_limit: Option<f32>,
        /// Sessions open at once: besides the host's, players may create this many less one.
        #[arg(long, default_value_t = 1, value_parser = max_sessions)]
        max_sessions: usize,
        /// How hard the guards are: easy, normal or hard (the level's tuning for it).
        #[arg(long, default_value_t = Difficulty::Normal)]
        difficulty: Difficulty,
        #[command(flatten)]
        fleet: FleetArgs,
    },
}

/// Flags of the servers that run for others (`host`, `serve`): health, metrics and the drain.
#[derive(clap::Args)]
pub(crate) struct FleetArgs {
    /// Serve `/healthz` (200 while the game loop runs, 503 when stalled or draining) and `/metrics`
    /// (Prometheus text format) on this TCP address.
    #[arg(long)]
    metrics: Option<SocketAddr>,
    /// Seconds a drain (the first SIGTERM or SIGINT; a second exits at once) waits for running heists
    /// to reach their result before it closes them.
    #[arg(long, default_value_t = heist_server::fleet::DEFAULT_DRAIN_LIMIT.as_secs_f32(), value_parser = positive_seconds)]
    drain_limit: f32,
}

/// Runs a server for others until it is over or drained: the fleet services `fleet` and `agones` ask
/// for, termination signals turned into a drain, Agones told `Shutdown` at the end.
fn run_server(mut server: heist_server::HostedServer, fleet: &FleetArgs, with_agones: bool) -> anyhow::Result<()> {
    use heist_server::fleet::{FleetOptions, FleetServices, agones, signals};
    signals::drain_on_termination(server.fleet.drain.clone()).context("cannot handle SIGTERM")?;
    let options = FleetOptions { metrics: fleet.metrics, agones: with_agones.then(agones::AgonesOptions::default) };
    let game = agones::GameServerInfo { registry: server.registry.clone(), advertised: server.advertised };
    let services = FleetServices::start(&server.fleet, game, &options)?;
    if let Some(http) = &services.http {
        println!("health and metrics on http://{}/healthz and /metrics", http.addr);
    }
    server.run();
    let failure = server.fleet.failure();
    services.shut_down();
    match failure {
        Some(why) => Err(anyhow::anyhow!(why)),
        None => Ok(()),
    }
}

/// What `host` and `serve` share.
struct Hosting {
    bind: SocketAddr,
    advertise: Option<SocketAddr>,
    code_ttl: u64,
    level: Option<PathBuf>,
    idle_end: f32,
    time_limit: Option<f32>,
    max_sessions: usize,
    shard_size: usize,
    ports: Vec<u16>,
    drain_limit: f32,
    difficulty: Difficulty,
}

impl Hosting {
    fn options(self, seed: Option<u64>, insecure: bool, host_session: bool) -> anyhow::Result<ServerOptions> {
        Ok(ServerOptions {
            level: load_level(self.level)?,
            game: GameOptions {
                seed: seed.unwrap_or_else(rand::random),
                random_rounds: seed.is_none(),
                idle_end_s: Some(self.idle_end),
                time_limit_s: self.time_limit,
                ends_unjoined: false,
                difficulty: self.difficulty,
            },
            host_session,
            max_sessions: self.max_sessions,
            bind: self.bind,
            token_bind: self.bind,
            insecure,
            clock: Clock::RealTime,
            echo_log: LogEcho::Tracing,
            abuse_limit: 50,
            advertise: self.advertise,
            code_ttl: Duration::from_secs(self.code_ttl.max(1) * 60),
            token_limits: Default::default(),
            intake_limits: Default::default(),
            drain_limit: Duration::from_secs_f32(self.drain_limit),
            stall_after: heist_server::fleet::STALL_AFTER,
            shard_size: self.shard_size,
            ports: self.ports,
        })
    }
}

fn print_address(server: &heist_server::HostedServer) {
    if server.advertised == server.addr {
        println!("hosting on {} (UDP game, TCP tokens)", server.addr);
    } else {
        println!("hosting on {} (UDP game, TCP tokens); players connect to {}", server.addr, server.advertised);
    }
    if server.shards.len() > 1 {
        let ports: Vec<String> = server.shards.iter().map(|s| s.advertised.port().to_string()).collect();
        println!("{} shards, each serving its sessions on a UDP port of its own: {}", ports.len(), ports.join(", "));
    }
}

/// Runs `serve` or `host`.
pub(crate) fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Host {
            bind,
            advertise,
            seed,
            code_ttl,
            level,
            insecure,
            idle_end,
            time_limit,
            max_sessions,
            difficulty,
            fleet,
        } => {
            if insecure {
                eprintln!("WARNING: --insecure: anyone who reaches {bind} can join as any role. LAN development only!");
            }
            let drain_limit = fleet.drain_limit;
            let hosting = Hosting {
                bind,
                advertise,
                code_ttl,
                level,
                idle_end,
                time_limit,
                max_sessions,
                shard_size: heist_server::DEFAULT_SHARD_SIZE,
                ports: Vec::new(),
                drain_limit,
                difficulty,
            };
            let server = build_server(hosting.options(seed, insecure, true)?)?;
            print_address(&server);
            if let Some(codes) = server.codes.clone() {
                println!("join code: {}", codes.current().describe());
                println!("type `rotate` and Enter for a new join code");
                std::thread::Builder::new().name("host-console".into()).spawn(move || {
                    for line in std::io::stdin().lock().lines().map_while(Result::ok) {
                        if line.trim() == "rotate" {
                            println!("new join code: {} (the old one no longer works)", codes.rotate().describe());
                        }
                    }
                })?;
            }
            run_server(server, &fleet, false)?;
            println!("the session is over");
            Ok(())
        }
        Command::Serve {
            mut bind,
            mut advertise,
            max_sessions,
            shard_size,
            code_ttl,
            level,
            idle_end,
            time_limit,
            difficulty,
            fleet,
            agones,
        } => {
            let mut ports = Vec::new();
            if agones && advertise.is_none() {
                // Players reach the pod at its node's address and host ports, which only Agones knows:
                // one port a shard, named `game`, `game-1`, `game-2`, ...
                use heist_server::fleet::agones::{AgonesOptions, game_port_name, public_ports};
                let names: Vec<String> = (0..max_sessions.div_ceil(shard_size)).map(game_port_name).collect();
                let (ip, found) = public_ports(&AgonesOptions::default(), &names)?;
                for (shard, (name, port)) in names.iter().zip(found).enumerate() {
                    ports.push(match port {
                        Some(p) => p,
                        None if shard == 0 && bind.port() != 0 => bind.port(),
                        None => anyhow::bail!(
                            "the GameServer has no `{name}` port for shard {shard} (--max-sessions {max_sessions} \
                             in shards of --shard-size {shard_size} need {} ports)",
                            names.len()
                        ),
                    });
                }
                bind.set_port(ports[0]);
                advertise = Some(SocketAddr::new(ip, ports[0]));
            }
            let drain_limit = fleet.drain_limit;
            let hosting = Hosting {
                bind,
                advertise,
                code_ttl,
                level,
                idle_end,
                time_limit,
                max_sessions,
                shard_size,
                ports,
                drain_limit,
                difficulty,
            };
            let server = build_server(hosting.options(None, false, false)?)?;
            print_address(&server);
            println!("serving up to {max_sessions} sessions: a player creates one and gets its join code");
            run_server(server, &fleet, agones)?;
            println!("drained: every session is over");
            Ok(())
        }
    }
}
