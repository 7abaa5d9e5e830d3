//! The binary's log: `tracing` to stderr, filtered by `RUST_LOG`, as text or one JSON object per line.

use std::io::IsTerminal as _;

use clap::ValueEnum;
use tracing_subscriber::EnvFilter;

/// How log lines are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// For people: time, level, target, message, fields.
    Text,
    /// For log collectors: one JSON object per line (timestamp, level, target, fields with the message).
    Json,
}

/// Installs the subscriber (and the bridge for libraries logging through `log`, like netcode). `default`
/// is the filter when `RUST_LOG` is unset; netcode's own per-packet lines stay off unless asked for, since
/// the intake reports refused datagrams itself, throttled.
pub fn init(format: Format, default: &str) {
    let filter =
        EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(format!("{default},renetcode=off")));
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal());
    let result = match format {
        Format::Text => builder.try_init(),
        Format::Json => builder.json().flatten_event(true).try_init(),
    };
    if let Err(e) = result {
        eprintln!("warning: no log output: {e}");
    }
}
