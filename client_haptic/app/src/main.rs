//! `client_haptic`: join a Phantom Heist session as Phantom (see `client_haptic::cli`).

use clap::Parser;
use client_haptic::cli::{Cli, Command};
use client_haptic::commands::{devices, join, practice};

/// Errors end the program on one line (`error: what: why`), never with a backtrace, even with
/// `RUST_BACKTRACE` set.
fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> anyhow::Result<()> {
    heist_client::signals::install();
    match Cli::parse().command {
        Command::Join(args) => join(&args),
        Command::Host(args) => client_haptic::host::host(&args),
        Command::Practice(args) => practice(&args),
        Command::Devices => devices(),
    }
}
