//! `client_vr`: join a Phantom Heist session as Vive (see `client_vr --help`).

use clap::Parser as _;
use client_vr::cli::{Cli, Command, join, xr_check};

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Join(args) => join(&args),
        Command::XrCheck => xr_check(),
    }
}
