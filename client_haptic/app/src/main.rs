//! `client_haptic`: join a Phantom Heist session as Phantom (see `client_haptic::cli`).

use clap::Parser;
use client_haptic::cli::{Cli, Command, devices, join, practice};

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Join(args) => join(&args),
        Command::Practice(args) => practice(&args),
        Command::Devices => devices(),
    }
}
