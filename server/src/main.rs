//! `heist-server`: host a Phantom Heist session, join one as a bot, or watch a whole demo heist.

mod counting;
mod logging;

use std::io::BufRead as _;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context as _;
use bevy::prelude::*;
use clap::{Parser, Subcommand, ValueEnum};
use heist_bots::{PhantomBotPlugin, ViveBotPlugin, ViveStyle};
use heist_server::game::GameOptions;
use heist_server::session::LogEcho;
use heist_server::{Clock, ServerOptions, build_server};
use heist_shared::level::Level;
use heist_shared::protocol::Role;
use heist_shared::rules::Difficulty;

#[derive(Parser)]
#[command(name = "heist-server", about = "Phantom Heist: the authoritative server, its demo and its bots")]
struct Cli {
    /// How log lines are written (stderr); `RUST_LOG` chooses which (e.g. `RUST_LOG=debug`).
    #[arg(long, value_enum, default_value_t = logging::Format::Text, global = true)]
    log_format: logging::Format,
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
enum Style {
    Careful,
    Reckless,
    Idle,
}

impl From<Style> for ViveStyle {
    fn from(s: Style) -> Self {
        match s {
            Style::Careful => ViveStyle::Careful,
            Style::Reckless => ViveStyle::Reckless,
            Style::Idle => ViveStyle::Idle,
        }
    }
}

#[derive(Subcommand)]
enum Command {
    /// Host a session on loopback with both bots, print the live log and the result.
    Demo {
        /// Seed for the copies and the guards (default 20: on normal, a heist the bots win after breaking
        /// glass in the west gallery, the sculpture hall and the treasury).
        #[arg(long, default_value_t = 20)]
        seed: u64,
        /// Level file (default: the shipped museum).
        #[arg(long)]
        level: Option<PathBuf>,
        /// How the Vive bot plays.
        #[arg(long, value_enum, default_value_t = Style::Careful)]
        vive: Style,
        /// Override the level's time limit, seconds.
        #[arg(long, value_parser = positive_seconds)]
        time_limit: Option<f32>,
        /// Heists in the session: after each result the bots ask for another round (a new seed).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
        rounds: u32,
        /// How hard the guards are: easy, normal or hard (the level's tuning for it). The demo shows
        /// normal, the museum as designed (docs/rules.md, "Bot status").
        #[arg(long, default_value_t = Difficulty::Normal)]
        difficulty: Difficulty,
    },
    /// Play one whole bot heist per seed (no live log) and print each result and the tally.
    Sweep {
        /// First seed.
        #[arg(long, default_value_t = 1)]
        from: u64,
        /// Last seed (inclusive).
        #[arg(long, default_value_t = 50)]
        to: u64,
        /// How the Vive bot plays.
        #[arg(long, value_enum, default_value_t = Style::Careful)]
        vive: Style,
        /// Difficulties to sweep, comma-separated (easy,normal,hard): a tally for each.
        #[arg(long, value_delimiter = ',', default_value = "normal")]
        difficulty: Vec<Difficulty>,
        /// Level file (default: the shipped museum): to try a level's own difficulty table.
        #[arg(long)]
        level: Option<PathBuf>,
        /// Heists played at once, each on a thread of its own (default: one per core). The results do
        /// not depend on it: a heist is deterministic for its seed.
        #[arg(long, value_parser = clap::value_parser!(u16).range(1..=256))]
        jobs: Option<u16>,
    },
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
    /// Play N bot pairs, each in its own session, against one server over loopback, and print what the
    /// server spends: CPU per session-tick, tick time, bytes per client.
    Load {
        /// Sessions (bot pairs).
        #[arg(long, default_value_t = 10, value_parser = max_sessions)]
        sessions: usize,
        /// Seconds of play measured, once every bot is in.
        #[arg(long, default_value_t = 30.0, value_parser = positive_seconds)]
        seconds: f32,
        /// Print one JSON object as the last line.
        #[arg(long)]
        json: bool,
        /// Serve `/healthz` and `/metrics` on this TCP address while the load runs.
        #[arg(long)]
        metrics: Option<SocketAddr>,
        /// Sessions a shard plays at most (as `serve --shard-size`).
        #[arg(long, default_value_t = heist_server::DEFAULT_SHARD_SIZE, value_parser = max_sessions)]
        shard_size: usize,
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
    /// Join a hosted session as a bot (restarted within a minute of losing its connection, it takes its
    /// seat back through the seat cache, `$XDG_CACHE_HOME/phantom-heist/seats`).
    Join {
        /// The host's game address.
        addr: SocketAddr,
        /// Join code printed by the host (or by the partner who created the session).
        #[arg(long, required_unless_present = "create")]
        code: Option<String>,
        /// Create a new session on the server instead, print its join code for a partner, and play it.
        #[arg(long, conflicts_with = "code")]
        create: bool,
        /// Role to play.
        #[arg(long)]
        role: Role,
        /// How a Vive bot plays.
        #[arg(long, value_enum, default_value_t = Style::Careful)]
        vive: Style,
        /// Heists to play: after each result but the last the bot asks for another round; after the last
        /// it leaves.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
        rounds: u32,
    },
}

/// Flags of the servers that run for others (`host`, `serve`): health, metrics and the drain.
#[derive(clap::Args)]
struct FleetArgs {
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
fn run_server(mut server: heist_server::HostedServer, fleet: &FleetArgs, agones: bool) -> anyhow::Result<()> {
    use heist_server::fleet::{FleetOptions, FleetServices, agones::AgonesOptions, signals};
    signals::drain_on_termination(server.fleet.drain.clone()).context("cannot handle SIGTERM")?;
    let options = FleetOptions { metrics: fleet.metrics, agones: agones.then(AgonesOptions::default) };
    let services = FleetServices::start(&server, &options)?;
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

/// The bot leaves a few seconds after the last round's result, or quits when the server lets it go or
/// it could not get back in after a lost connection, saying why.
#[allow(clippy::too_many_arguments)]
fn leave_after_the_last_round(
    rounds: Res<heist_bots::Rounds>,
    inbox: Res<heist_client::Inbox>,
    session: Query<&heist_shared::protocol::SessionView>,
    time: Res<Time<Real>>,
    mut over_at: Local<Option<f64>>,
    mut leaving: ResMut<heist_client::Leaving>,
    link: Res<heist_client::Link>,
    reconnect: Res<heist_client::Reconnect>,
    mut was_reconnect: Local<heist_client::Reconnect>,
    mut exit: MessageWriter<AppExit>,
) {
    use heist_client::{Link, Reconnect};
    use heist_shared::protocol::Phase;
    let now = time.elapsed_secs_f64();
    if let Some(reason) = &inbox.disconnect {
        println!("{}", heist_client::notice::disconnect_notice(reason));
        exit.write(AppExit::Success);
        return;
    }
    if *reconnect != *was_reconnect {
        if let Some(line) = heist_client::notice::reconnect_notice(&was_reconnect, &reconnect) {
            println!("{line}");
        }
        *was_reconnect = reconnect.clone();
    }
    if heist_client::connection_over(*link, &inbox, &reconnect) {
        if !matches!(*reconnect, Reconnect::GaveUp(_)) {
            println!("{}", heist_client::notice::link_notice(Link::Up, *link).unwrap_or_default());
        }
        exit.write(AppExit::Success);
        return;
    }
    let finished = session.single().is_ok_and(|s| matches!(s.phase, Phase::Won | Phase::Lost(_)));
    if !finished || inbox.current_round() < rounds.0 {
        *over_at = None;
        return;
    }
    let at = *over_at.get_or_insert(now);
    if now - at > 2.0 {
        leaving.start(now);
    }
}

/// A number of sessions for a flag: 1 to the most one server hosts.
fn max_sessions(text: &str) -> Result<usize, String> {
    let max = heist_server::net::MAX_SESSIONS;
    match text.parse::<usize>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        Ok(n) => Err(format!("must be 1 to {max} sessions, got {n}")),
        Err(e) => Err(format!("not a number of sessions ({e})")),
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

/// A number of seconds for a flag: finite and above zero.
fn positive_seconds(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(s) if s.is_finite() && s > 0.0 => Ok(s),
        Ok(_) => Err(format!("must be a positive number of seconds, got {text}")),
        Err(e) => Err(format!("not a number of seconds ({e})")),
    }
}

fn load_level(path: Option<PathBuf>) -> anyhow::Result<Level> {
    match path {
        Some(p) => Ok(Level::load(p)?),
        None => Ok(Level::museum()),
    }
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let quiet = matches!(cli.command, Command::Demo { .. } | Command::Sweep { .. } | Command::Load { .. });
    logging::init(cli.log_format, if quiet { "warn" } else { "info" });
    match run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Demo { seed, level, vive, time_limit, rounds, difficulty } => {
            let mut options = ServerOptions::local_test(seed);
            options.level = load_level(level)?;
            options.game = GameOptions { seed, time_limit_s: time_limit, difficulty, ..Default::default() };
            options.echo_log = LogEcho::Stdout;
            println!(
                "Phantom Heist demo: {} with seed {seed} on {difficulty}, both bots over loopback UDP",
                options.level.name
            );
            heist_server::demo::run_demo(options, vive.into(), rounds)?;
            Ok(())
        }
        Command::Sweep { from, to, vive, difficulty, level, jobs } => {
            anyhow::ensure!(from <= to, "--from {from} is after --to {to}");
            let level = load_level(level)?;
            let jobs = jobs.map_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()), usize::from);
            let mut tallies = Vec::new();
            for d in difficulty {
                let each = |seed: u64, line: &str| println!("{d:>6} seed {seed:>4}: {line}");
                tallies.push((d, heist_server::demo::sweep(&level, from..=to, vive.into(), d, jobs, each)?));
            }
            for (d, tally) in tallies {
                println!("{d}: {tally}");
            }
            Ok(())
        }
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
        Command::Load { sessions, seconds, json, metrics, shard_size } => {
            let options = heist_server::load::LoadOptions {
                sessions,
                seconds,
                style: ViveStyle::Careful,
                metrics,
                shard_size,
                heap: Some(counting::PROBE),
            };
            let report = heist_server::load::run_load(&options, |line| println!("{line}"))?;
            println!("{report}");
            if json {
                println!("{}", serde_json::to_string(&report)?);
            }
            Ok(())
        }
        Command::Join { addr, code, create, role, vive, rounds } => {
            let cache = heist_client::SeatCache::in_default_dir();
            let timeout = Duration::from_secs(5);
            let joining = match (code, create) {
                (Some(code), _) => heist_client::join_or_resume(addr, &code, role, cache.as_ref(), timeout)
                    .with_context(|| format!("joining {addr} as {role}"))?,
                (None, _) => {
                    let (code, token) = heist_client::create_session(addr, role, timeout)
                        .with_context(|| format!("creating a session on {addr}"))?;
                    println!("created a session on {addr}; join code: {code}");
                    heist_client::Joining { token, resuming: false }
                }
            };
            let mut app = App::new();
            app.add_plugins(
                MinimalPlugins.set(bevy::app::ScheduleRunnerPlugin::run_loop(Duration::from_secs_f64(1.0 / 60.0))),
            )
            .add_plugins(heist_client::ClientNetPlugin)
            .insert_resource(heist_bots::Rounds(rounds))
            .add_systems(Update, leave_after_the_last_round);
            match role {
                Role::Vive => app.add_plugins(ViveBotPlugin { style: vive.into() }),
                Role::Phantom => app.add_plugins(PhantomBotPlugin::default()),
            };
            app.finish();
            app.cleanup();
            heist_client::connect(&mut app, joining.token)?;
            heist_client::hold_seat(&mut app, cache, addr, role);
            if joining.resuming {
                println!("took the {role} seat back at {addr}");
            } else {
                println!("joined {addr} as {role}");
            }
            app.run();
            Ok(())
        }
    }
}
