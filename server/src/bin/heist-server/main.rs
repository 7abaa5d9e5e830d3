//! `heist-server`: serve many Phantom Heist sessions or host one; built with the `bots` feature, also
//! join a session as a bot, watch a whole demo heist, sweep seeds and measure what sessions cost.

#[cfg(feature = "bots")]
mod bots;
#[cfg(feature = "bots")]
mod counting;
mod logging;
mod serving;

use std::path::PathBuf;

use clap::{Parser, Subcommand};
use heist_shared::level::Level;

/// mimalloc instead of glibc's allocator: a session's tick 12–26 % cheaper in `load` (docs/decisions.md,
/// issue 48). A build with `bots` wraps it to count the server's heap (`counting.rs`).
#[cfg(not(feature = "bots"))]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(name = "heist-server", about = "Phantom Heist: the authoritative server, its demo and its bots")]
struct Cli {
    /// How log lines are written (stderr); `RUST_LOG` chooses which (e.g. `RUST_LOG=debug`).
    #[arg(long, value_enum, default_value_t = logging::Format::Text, global = true)]
    log_format: logging::Format,
    #[command(subcommand)]
    command: Command,
}

/// The commands: the bots' (a build with the `bots` feature) and the servers' for players.
#[derive(Subcommand)]
enum Command {
    #[cfg(feature = "bots")]
    #[command(flatten)]
    Bots(bots::Command),
    #[command(flatten)]
    Serving(serving::Command),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let quiet = match &cli.command {
        #[cfg(feature = "bots")]
        Command::Bots(command) => command.quiet(),
        Command::Serving(_) => false,
    };
    logging::init(cli.log_format, if quiet { "warn" } else { "info" });
    let result = match cli.command {
        #[cfg(feature = "bots")]
        Command::Bots(command) => bots::run(command),
        Command::Serving(command) => serving::run(command),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// A number of sessions for a flag: 1 to the most one server hosts.
pub(crate) fn max_sessions(text: &str) -> Result<usize, String> {
    let max = heist_server::net::MAX_SESSIONS;
    match text.parse::<usize>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        Ok(n) => Err(format!("must be 1 to {max} sessions, got {n}")),
        Err(e) => Err(format!("not a number of sessions ({e})")),
    }
}

/// A number of seconds for a flag: finite and above zero.
pub(crate) fn positive_seconds(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(s) if s.is_finite() && s > 0.0 => Ok(s),
        Ok(_) => Err(format!("must be a positive number of seconds, got {text}")),
        Err(e) => Err(format!("not a number of seconds ({e})")),
    }
}

pub(crate) fn load_level(path: Option<PathBuf>) -> anyhow::Result<Level> {
    match path {
        Some(p) => Ok(Level::load(p)?),
        None => Ok(Level::museum()),
    }
}
