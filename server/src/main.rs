//! `heist-server`: host a Phantom Heist session, join one as a bot, or watch a whole demo heist.

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
        /// Seed for the copies and the guards (default 10: a heist the bots win).
        #[arg(long, default_value_t = 10)]
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
    },
    /// Join a hosted session as a bot (restarted within a minute of losing its connection, it takes its
    /// seat back through the seat cache, `$XDG_CACHE_HOME/phantom-heist/seats`).
    Join {
        /// The host's game address.
        addr: SocketAddr,
        /// Join code printed by the host.
        #[arg(long)]
        code: String,
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
    let quiet = matches!(cli.command, Command::Demo { .. } | Command::Sweep { .. });
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
        Command::Demo { seed, level, vive, time_limit, rounds } => {
            let mut options = ServerOptions::local_test(seed);
            options.level = load_level(level)?;
            options.game = GameOptions { seed, time_limit_s: time_limit, ..Default::default() };
            options.echo_log = LogEcho::Stdout;
            println!("Phantom Heist demo: {} with seed {seed}, both bots over loopback UDP", options.level.name);
            heist_server::demo::run_demo(options, vive.into(), rounds)?;
            Ok(())
        }
        Command::Sweep { from, to, vive } => {
            anyhow::ensure!(from <= to, "--from {from} is after --to {to}");
            let tally =
                heist_server::demo::sweep(from..=to, vive.into(), |seed, line| println!("seed {seed:>4}: {line}"))?;
            println!("{tally}");
            Ok(())
        }
        Command::Host { bind, advertise, seed, code_ttl, level, insecure, idle_end, time_limit } => {
            if insecure {
                eprintln!("WARNING: --insecure: anyone who reaches {bind} can join as any role. LAN development only!");
            }
            let options = ServerOptions {
                level: load_level(level)?,
                game: GameOptions {
                    seed: seed.unwrap_or_else(rand::random),
                    random_rounds: seed.is_none(),
                    idle_end_s: Some(idle_end),
                    time_limit_s: time_limit,
                },
                bind,
                token_bind: bind,
                insecure,
                clock: Clock::RealTime,
                echo_log: LogEcho::Tracing,
                abuse_limit: 50,
                advertise,
                code_ttl: Duration::from_secs(code_ttl.max(1) * 60),
                token_limits: Default::default(),
            };
            let mut server = build_server(options)?;
            if server.advertised == server.addr {
                println!("hosting on {} (UDP game, TCP tokens)", server.addr);
            } else {
                println!("hosting on {} (UDP game, TCP tokens); players connect to {}", server.addr, server.advertised);
            }
            if let Some(tokens) = &server.tokens {
                println!("join code: {}", tokens.codes.current().describe());
                println!("type `rotate` and Enter for a new join code");
                let codes = tokens.codes.clone();
                std::thread::Builder::new().name("host-console".into()).spawn(move || {
                    for line in std::io::stdin().lock().lines().map_while(Result::ok) {
                        if line.trim() == "rotate" {
                            println!("new join code: {} (the old one no longer works)", codes.rotate().describe());
                        }
                    }
                })?;
            }
            server.app.run();
            println!("the session is over");
            Ok(())
        }
        Command::Join { addr, code, role, vive, rounds } => {
            let cache = heist_client::SeatCache::in_default_dir();
            let joining = heist_client::join_or_resume(addr, &code, role, cache.as_ref(), Duration::from_secs(5))
                .with_context(|| format!("joining {addr} as {role}"))?;
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
