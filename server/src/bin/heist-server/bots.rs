//! The commands that play bots against a server: `demo` (a whole heist, live), `sweep` (a tally over
//! seeds), `load` (what many sessions cost) and `join` (a bot for a session someone hosts).

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context as _;
use bevy::prelude::*;
use clap::{Subcommand, ValueEnum};
use heist_bots::{PhantomBotPlugin, ViveBotPlugin, ViveStyle};
use heist_server::ServerOptions;
use heist_server::game::GameOptions;
use heist_server::session::LogEcho;
use heist_shared::protocol::Role;
use heist_shared::rules::Difficulty;

use crate::{counting, load_level, max_sessions, positive_seconds};

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum Style {
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
pub(crate) enum Command {
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
        /// Players come and go: every this many seconds of game time each session loses a player, who
        /// comes back with the seat's ticket 5 s later, or both leave and a new pair creates a session.
        #[arg(long, value_parser = positive_seconds)]
        churn: Option<f32>,
        /// Before every measured tick write this many MB (1024 if no figure is given; more than the
        /// machine's last-level cache), so that runs of any size measure the server from the same cold
        /// cache: without it a big run's bots evict the server's data between ticks and a small run's
        /// do not.
        #[arg(long, num_args = 0..=1, default_missing_value = "1024", value_name = "MB",
              value_parser = clap::value_parser!(u32).range(1..=i64::from(heist_server::load::Evictor::MAX_MB)))]
        cold_cache: Option<u32>,
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

impl Command {
    /// Whether the command's own output is all a user wants to read (the log says only warnings).
    pub(crate) fn quiet(&self) -> bool {
        matches!(self, Command::Demo { .. } | Command::Sweep { .. } | Command::Load { .. })
    }
}

/// Runs a bots' command.
pub(crate) fn run(command: Command) -> anyhow::Result<()> {
    match command {
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
        Command::Load { sessions, seconds, json, metrics, shard_size, churn, cold_cache } => {
            let options = heist_server::load::LoadOptions {
                sessions,
                seconds,
                style: ViveStyle::Careful,
                metrics,
                shard_size,
                heap: Some(counting::PROBE),
                churn,
                cold_cache_mb: cold_cache,
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
