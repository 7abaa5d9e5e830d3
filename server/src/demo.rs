//! A whole heist in one process: the real server, both bots as real clients, real UDP on loopback,
//! secure tokens, and a clock stepped by hand so a ten-minute heist runs in seconds.
//!
//! The `demo` subcommand and the end-to-end tests use this.

use std::time::Duration;

use anyhow::Context as _;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use heist_bots::{PhantomBotPlugin, Rounds, ViveBotPlugin, ViveBrain, ViveStyle};
use heist_client::{ClientNetPlugin, request_token};
use heist_shared::protocol::{Phase, Role, TICK_HZ};
use heist_transport::renetcode::ConnectToken;

use crate::{HostedServer, ServerOptions, build_server};

/// How long a token request may take.
const TOKEN_TIMEOUT: Duration = Duration::from_secs(5);

/// A client app driven by hand: minimal plugins, stepped clock, the client core.
pub fn stepped_client_app() -> App {
    let mut app = App::new();
    app.add_plugins(MinimalPlugins)
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(1.0 / TICK_HZ)))
        .add_plugins(ClientNetPlugin);
    app
}

/// A connect token for `role` from `server`'s endpoint with its current code, as a player gets one.
pub fn token(server: &HostedServer, role: Role) -> anyhow::Result<ConnectToken> {
    let tokens = server.tokens.as_ref().context("the server runs without a token endpoint")?;
    let code = server.join_code().context("the server has no host session")?;
    Ok(request_token(tokens.addr, &code.code, role, TOKEN_TIMEOUT)?)
}

/// Joins `server` as `role` through its token endpoint; `plugins` add the bot (or test probes).
pub fn join(server: &HostedServer, role: Role, setup: impl FnOnce(&mut App)) -> anyhow::Result<App> {
    client_with_token(token(server, role)?, setup)
}

/// A stepped client connecting with `token`; `setup` adds the bot (or test probes).
pub fn client_with_token(token: ConnectToken, setup: impl FnOnce(&mut App)) -> anyhow::Result<App> {
    let mut app = stepped_client_app();
    setup(&mut app);
    app.finish();
    app.cleanup();
    heist_client::connect(&mut app, token)?;
    Ok(app)
}

/// A server and its two bot clients, stepped together.
pub struct Heist {
    /// The server.
    pub server: HostedServer,
    /// Vive's client.
    pub vive: App,
    /// Phantom's client.
    pub phantom: App,
    /// Ticks stepped so far.
    pub ticks: u64,
    /// Each round's end, in order.
    pub results: Vec<RoundResult>,
}

/// How one round ended, read the tick it ended (a rematch may replace the game soon after).
#[derive(Clone, Debug, PartialEq)]
pub struct RoundResult {
    /// The round (1 for the first).
    pub round: u32,
    /// Its seed.
    pub seed: u64,
    /// Its final phase.
    pub phase: Phase,
    /// Game time it lasted, seconds.
    pub elapsed_s: f32,
    /// `RESULT: …`.
    pub line: String,
}

impl Heist {
    /// Starts a server with `options` and joins both bots.
    pub fn start(options: ServerOptions, style: ViveStyle) -> anyhow::Result<Self> {
        Self::join(build_server(options)?, style)
    }

    /// Joins both bots to a running `server`.
    pub fn join(server: HostedServer, style: ViveStyle) -> anyhow::Result<Self> {
        Self::join_for_rounds(server, style, 1)
    }

    /// Both bots join and will ask for another round after each result until `rounds` were played.
    pub fn join_for_rounds(server: HostedServer, style: ViveStyle, rounds: u32) -> anyhow::Result<Self> {
        let vive = join(&server, Role::Vive, |app| {
            app.add_plugins(ViveBotPlugin { style }).insert_resource(Rounds(rounds));
        })?;
        let phantom = join(&server, Role::Phantom, |app| {
            app.add_plugins(PhantomBotPlugin::default()).insert_resource(Rounds(rounds));
        })?;
        Ok(Self { server, vive, phantom, ticks: 0, results: Vec::new() })
    }

    /// After a result: steps until the next round is on (true) or `max_s` of stepped time passed, or the
    /// session closed (false).
    pub fn await_next_round(&mut self, max_s: f32) -> bool {
        let round = self.results.last().map_or(1, |r| r.round);
        let begun = |g: &crate::game::Game| g.round > round && g.is_running();
        if begun(self.server.game()) {
            return true;
        }
        for _ in 0..(f64::from(max_s) * TICK_HZ) as u64 {
            self.step();
            let g = self.server.game();
            if begun(g) {
                return true;
            }
            if g.closed {
                return false;
            }
        }
        false
    }

    /// One tick for everyone.
    pub fn step(&mut self) {
        self.server.update();
        self.vive.update();
        self.phantom.update();
        self.ticks += 1;
    }

    /// Steps until the session ends or `max_game_s` of heist time passes (plus a bounded lobby);
    /// returns the final phase.
    pub fn run(&mut self, max_game_s: f32) -> Phase {
        let max_ticks = ((max_game_s as f64 + 30.0) * TICK_HZ) as u64;
        let trace = std::env::var_os("HEIST_TRACE").is_some();
        let mut goal_shown = String::new();
        for _ in 0..max_ticks {
            self.step();
            let doing = if trace { self.vive.world().resource::<ViveBrain>().doing() } else { None };
            if let Some((goal, decision)) = &doing
                && *goal != goal_shown
            {
                println!("  t={:.1} Vive bot: {goal} (then {decision})", self.server.game().elapsed_s);
                goal_shown.clone_from(goal);
            }
            if trace && self.ticks.is_multiple_of(30) {
                let g = self.server.game();
                let guards: Vec<String> = g
                    .guards
                    .iter()
                    .map(|gd| {
                        format!(
                            "{}({:.1},{:.1} f{:.1} {:?})",
                            gd.name, gd.position.x, gd.position.y, gd.facing, gd.alert
                        )
                    })
                    .collect();
                println!(
                    "  t={:.1} vive=({:.1},{:.1}) {:?} seq={} queued={} carry={:?} {} | {}",
                    g.elapsed_s,
                    g.vive.position.x,
                    g.vive.position.y,
                    g.vive.stance,
                    g.vive.last_input_seq,
                    g.vive.inputs.len(),
                    g.vive.carrying,
                    doing.map_or("", |(_, decision)| decision),
                    guards.join(" ")
                );
            }
            let g = self.server.game();
            if !g.is_running() {
                let phase = g.phase;
                self.results.push(RoundResult {
                    round: g.round,
                    seed: g.seed,
                    phase,
                    elapsed_s: g.elapsed_s,
                    line: crate::session::result_line(g).unwrap_or_default(),
                });
                // A few more ticks let the final messages reach the clients.
                for _ in 0..10 {
                    self.step();
                }
                return phase;
            }
        }
        self.server.game().phase
    }
}

/// The heist's time limit on its difficulty, seconds.
fn time_limit(options: &ServerOptions) -> f32 {
    let scale = options.level.tuning(options.game.difficulty).time_scale;
    options.game.time_limit_s.unwrap_or(options.level.time_limit_s * scale)
}

/// Plays a whole heist with bots to its end (or a little past its time limit); returns the heist, the
/// final phase and the result line.
fn play_to_the_end(options: ServerOptions, style: ViveStyle) -> anyhow::Result<(Heist, Phase, String)> {
    let limit = time_limit(&options);
    let mut heist = Heist::start(options, style)?;
    let phase = heist.run(limit + 5.0);
    let result = heist.results.last().map_or_else(|| format!("RESULT: unfinished ({phase:?})"), |r| r.line.clone());
    Ok((heist, phase, result))
}

/// Runs the demo: `rounds` heists in one session, the bots asking for another round after each result;
/// prints each round's result line. Returns the last round's phase.
pub fn run_demo(options: ServerOptions, style: ViveStyle, rounds: u32) -> anyhow::Result<Phase> {
    let limit = time_limit(&options);
    let rounds = rounds.max(1);
    let mut heist = Heist::join_for_rounds(build_server(options)?, style, rounds)?;
    let mut phase = heist.run(limit + 5.0);
    for round in 2..=rounds {
        if !heist.await_next_round(30.0) {
            println!("round {round} did not begin");
            break;
        }
        phase = heist.run(limit + 5.0);
    }
    for (name, app) in [("Vive", &heist.vive), ("Phantom", &heist.phantom)] {
        let inbox = app.world().resource::<heist_client::Inbox>();
        if !inbox.refusals.is_empty() {
            println!(
                "{name} bot had {} refusals, first: {:?}",
                inbox.refusals.len(),
                &inbox.refusals[..inbox.refusals.len().min(5)]
            );
        }
    }
    if heist.results.is_empty() {
        println!("RESULT: unfinished ({phase:?})");
    }
    for r in &heist.results {
        let prefix = if rounds > 1 { format!("round {}: ", r.round) } else { String::new() };
        println!("{prefix}{} after {:.1} s of game time", r.line, r.elapsed_s);
    }
    Ok(phase)
}

/// Outcomes of many bot heists.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    /// Seeds won.
    pub won: Vec<u64>,
    /// Seeds lost because a guard caught Vive.
    pub caught: Vec<u64>,
    /// Seeds lost for any other reason (the timer, the alarm).
    pub other: Vec<u64>,
    /// Catches by guard and room ("Clara in the west_gallery"), with their count.
    pub caught_where: std::collections::BTreeMap<String, u32>,
    /// Seconds the Vive bot spent under each of its decisions, summed over the heists.
    pub time_in: std::collections::BTreeMap<&'static str, f32>,
    /// Seconds the Vive bot spent carrying something, summed over the heists.
    pub carrying_s: f32,
}

impl Tally {
    /// Adds one finished heist.
    fn add(&mut self, outcome: Outcome) {
        match outcome.phase {
            Phase::Won => self.won.push(outcome.seed),
            Phase::Lost(heist_shared::protocol::LossReason::Caught) => self.caught.push(outcome.seed),
            _ => self.other.push(outcome.seed),
        }
        if let Some(place) = outcome.caught_where {
            *self.caught_where.entry(place).or_default() += 1;
        }
        let (time_in, carrying_s) = outcome.spent;
        for (decision, s) in time_in {
            *self.time_in.entry(decision).or_default() += s;
        }
        self.carrying_s += carrying_s;
    }
}

/// One finished heist of a sweep.
struct Outcome {
    seed: u64,
    phase: Phase,
    /// The seed's line: result, who caught Vive where, where the bot's time went.
    line: String,
    /// "Clara in the west_gallery" when a guard caught Vive.
    caught_where: Option<String>,
    /// Where the bot's time went ([`ViveBrain::time_spent`]).
    spent: TimeSpent,
}

/// Plays one whole bot heist on `level` with `seed`.
fn play_seed(
    level: &heist_shared::level::Level,
    seed: u64,
    style: ViveStyle,
    difficulty: heist_shared::rules::Difficulty,
) -> anyhow::Result<Outcome> {
    let mut options = ServerOptions::local_test(seed);
    options.level = level.clone();
    options.game.difficulty = difficulty;
    let (heist, phase, result) = play_to_the_end(options, style)?;
    let game = heist.server.game();
    let caught_where = caught_where(game);
    let by = caught_where.as_ref().map(|w| format!(" by {w}")).unwrap_or_default();
    let spent = heist.vive.world().resource::<ViveBrain>().time_spent();
    let line = format!("{result}{by} after {:.1} s ({})", game.elapsed_s, time_line(&spent));
    Ok(Outcome { seed, phase, line, caught_where, spent })
}

/// "Clara in the west_gallery" when a guard caught Vive.
fn caught_where(game: &crate::game::Game) -> Option<String> {
    let (guard, at) = game.caught_by?;
    let room = game.level.room_at(at).map_or("a doorway", |r| game.level.rooms[r].id.as_str());
    Some(format!("{} in the {room}", game.guards[guard].name))
}

/// The Vive bot's seconds per decision and seconds carrying ([`ViveBrain::time_spent`]).
type TimeSpent = (Vec<(&'static str, f32)>, f32);

/// Where one heist's bot time went, as "decision 12 s, …; carrying 40 s".
fn time_line((time_in, carrying_s): &TimeSpent) -> String {
    let parts: Vec<String> = time_in.iter().map(|(d, s)| format!("{d} {s:.0} s")).collect();
    format!("{}; carrying {carrying_s:.0} s", parts.join(", "))
}

impl std::fmt::Display for Tally {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = self.won.len() + self.caught.len() + self.other.len();
        write!(
            f,
            "won {} of {n} ({:.1}%), caught {}, other losses {}; winning seeds: {:?}",
            self.won.len(),
            100.0 * self.won.len() as f64 / n.max(1) as f64,
            self.caught.len(),
            self.other.len(),
            self.won
        )?;
        if !self.caught_where.is_empty() {
            let mut by: Vec<_> = self.caught_where.iter().collect();
            by.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
            let by: Vec<String> = by.iter().map(|(w, n)| format!("{w} ×{n}")).collect();
            write!(f, "\n  caught by: {}", by.join(", "))?;
        }
        let total: f32 = self.time_in.values().sum();
        if total > 0.0 {
            let mut by: Vec<_> = self.time_in.iter().collect();
            by.sort_by(|a, b| b.1.total_cmp(a.1));
            let by: Vec<String> = by.iter().map(|(d, s)| format!("{d} {:.0}%", 100.0 * *s / total)).collect();
            write!(f, "\n  bot's time: {}; carrying {:.0}%", by.join(", "), 100.0 * self.carrying_s / total)?;
        }
        Ok(())
    }
}

/// Plays one whole heist per seed on `level` and tallies the outcomes, `jobs` heists at a time (each on
/// a thread of its own; a heist is deterministic for its seed whatever else runs); `each` gets every
/// seed's result line in the order of `seeds`, as soon as it and the seeds before it have finished.
pub fn sweep(
    level: &heist_shared::level::Level,
    seeds: impl IntoIterator<Item = u64>,
    style: ViveStyle,
    difficulty: heist_shared::rules::Difficulty,
    jobs: usize,
    mut each: impl FnMut(u64, &str),
) -> anyhow::Result<Tally> {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let seeds: Vec<u64> = seeds.into_iter().collect();
    let (next, stop) = (AtomicUsize::new(0), AtomicBool::new(false));
    let (sent, finished) = std::sync::mpsc::channel();
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, seeds.len().max(1)) {
            let (sent, seeds, next, stop) = (sent.clone(), &seeds, &next, &stop);
            scope.spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&seed) = seeds.get(i) else { break };
                    if sent.send((i, play_seed(level, seed, style, difficulty))).is_err() {
                        break;
                    }
                }
            });
        }
        drop(sent);
        // Lines and the tally in seed order, whatever order the heists finish in.
        let mut tally = Tally::default();
        let mut waiting = std::collections::BTreeMap::new();
        let mut due = 0;
        for (i, outcome) in finished {
            waiting.insert(i, outcome);
            while let Some(outcome) = waiting.remove(&due) {
                let outcome = outcome.inspect_err(|_| stop.store(true, Ordering::Relaxed))?;
                each(outcome.seed, &outcome.line);
                tally.add(outcome);
                due += 1;
            }
        }
        Ok(tally)
    })
}
