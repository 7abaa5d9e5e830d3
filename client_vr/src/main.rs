//! `client_vr`: join a Phantom Heist session as Vive (see `client_vr --help`).

use clap::Parser as _;
use client_vr::cli::{Cli, Command, host, join, xr_check};

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
        Command::Host(args) => host(&args),
        Command::XrCheck => xr_check(),
    }
}
