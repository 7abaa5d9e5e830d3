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
        #[arg(long)]
        time_limit: Option<f32>,
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
    },
    /// Join a hosted session as a bot.
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
    },
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
        Command::Demo { seed, level, vive, time_limit } => {
            let mut options = ServerOptions::local_test(seed);
            options.level = load_level(level)?;
            options.game = GameOptions { seed, time_limit_s: time_limit };
            options.echo_log = LogEcho::Stdout;
            println!("Phantom Heist demo: {} with seed {seed}, both bots over loopback UDP", options.level.name);
            heist_server::demo::run_demo(options, vive.into())?;
            Ok(())
        }
        Command::Sweep { from, to, vive } => {
            anyhow::ensure!(from <= to, "--from {from} is after --to {to}");
            let tally =
                heist_server::demo::sweep(from..=to, vive.into(), |seed, line| println!("seed {seed:>4}: {line}"))?;
            println!("{tally}");
            Ok(())
        }
        Command::Host { bind, advertise, seed, code_ttl, level, insecure } => {
            if insecure {
                eprintln!("WARNING: --insecure: anyone who reaches {bind} can join as any role. LAN development only!");
            }
            let options = ServerOptions {
                level: load_level(level)?,
                game: GameOptions { seed: seed.unwrap_or_else(rand::random), time_limit_s: None },
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
            Ok(())
        }
        Command::Join { addr, code, role, vive } => {
            let token = heist_client::request_token(addr, &code, role, Duration::from_secs(5))
                .with_context(|| format!("joining {addr} as {role}"))?;
            let mut app = App::new();
            app.add_plugins(
                MinimalPlugins.set(bevy::app::ScheduleRunnerPlugin::run_loop(Duration::from_secs_f64(1.0 / 60.0))),
            )
            .add_plugins(heist_client::ClientNetPlugin);
            match role {
                Role::Vive => app.add_plugins(ViveBotPlugin { style: vive.into() }),
                Role::Phantom => app.add_plugins(PhantomBotPlugin::default()),
            };
            app.finish();
            app.cleanup();
            heist_client::connect(&mut app, token)?;
            println!("joined {addr} as {role}");
            app.run();
            Ok(())
        }
    }
}
