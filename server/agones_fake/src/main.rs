//! `agones-fake`: the fake Agones SDK server on its own, printing every call a game server makes, so
//! `heist-server serve --agones` can be tried on a machine without Agones:
//!
//! ```text
//! agones-fake --port 9357 --counter sessions=32 --list players=64
//! AGONES_SDK_GRPC_PORT=9357 heist-server serve --agones
//! ```

use std::time::Duration;

use agones_fake::{Declared, FakeAgones};
use clap::Parser;

#[derive(Parser)]
#[command(name = "agones-fake", about = "A local stand-in for the Agones SDK server that prints every call")]
struct Cli {
    /// Port on 127.0.0.1 (Agones' default SDK port is 9357).
    #[arg(long, default_value_t = 9357)]
    port: u16,
    /// A Counter the GameServer spec declares, NAME=CAPACITY (repeatable).
    #[arg(long = "counter", value_parser = named_capacity)]
    counters: Vec<(String, i64)>,
    /// A List the GameServer spec declares, NAME=CAPACITY (repeatable).
    #[arg(long = "list", value_parser = named_capacity)]
    lists: Vec<(String, i64)>,
    /// A port in the game server's status, NAME=PORT (repeatable; `serve --agones --bind 0.0.0.0:0`
    /// binds the `game` one, as with Agones' Passthrough policy).
    #[arg(long = "port-of", value_parser = named_capacity)]
    ports: Vec<(String, i64)>,
    /// Allocate the game server after this many seconds, as Agones' allocator would.
    #[arg(long)]
    allocate_after: Option<f64>,
}

fn named_capacity(text: &str) -> Result<(String, i64), String> {
    let (name, capacity) = text.split_once('=').ok_or_else(|| format!("expected NAME=CAPACITY, got {text}"))?;
    let capacity = capacity.parse::<i64>().map_err(|e| format!("capacity of {name}: {e}"))?;
    Ok((name.to_owned(), capacity))
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let bind = std::net::SocketAddr::from(([127, 0, 0, 1], cli.port));
    let ports = cli.ports.into_iter().filter_map(|(n, p)| Some((n, u16::try_from(p).ok()?))).collect();
    let fake = match FakeAgones::start(bind, Declared { counters: cli.counters, lists: cli.lists, ports }) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: cannot serve on {bind}: {e}");
            return std::process::ExitCode::FAILURE;
        }
    };
    println!("fake Agones SDK server on {} (AGONES_SDK_GRPC_PORT={})", fake.addr, fake.addr.port());
    let started = std::time::Instant::now();
    let mut allocate_at = cli.allocate_after.map(Duration::from_secs_f64);
    let (mut printed, mut pings) = (0, 0);
    loop {
        std::thread::sleep(Duration::from_millis(100));
        let r = fake.recorded();
        for call in &r.calls[printed..] {
            println!("{:8.2} s  {call}", started.elapsed().as_secs_f64());
        }
        printed = r.calls.len();
        if r.health_pings.len() / 10 > pings / 10 {
            println!("{:8.2} s  ({} health pings)", started.elapsed().as_secs_f64(), r.health_pings.len());
        }
        pings = r.health_pings.len();
        if allocate_at.is_some_and(|at| started.elapsed() >= at) {
            allocate_at = None;
            fake.allocate();
        }
    }
}
