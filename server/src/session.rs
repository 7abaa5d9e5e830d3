//! Sessions in the ECS: each hosted session is an entity with a [`Session`] (its [`Game`], stepped in
//! `FixedUpdate`, its players and its log); its state is mirrored in `PostUpdate` into replicated
//! entities related to it ([`MirrorOf`]) and tagged with its [`SessionTag`], the visibility filter that
//! shows them only to that session's players.

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use heist_shared::protocol::{
    Audience, CaseId, CaseView, Cases, GameEvent, GuardAlert, GuardView, Guards, ItemId, ItemView, Items, LossReason,
    PhantomTool, Phase, Role, SessionView, VerdictOutcome, ViveAvatar,
};

use crate::game::Game;
use crate::net::seats::Roles;
use crate::net::seats::Seats;

/// One hosted session: its game, who plays it, and its log.
#[derive(Component)]
pub struct Session {
    /// Its id, as its players' tokens carry it.
    pub id: u64,
    /// The authoritative game.
    pub game: Game,
    /// Its log.
    pub log: SessionLog,
    /// Which client plays which role.
    pub roles: Roles,
    /// Its seats, shared with the token endpoint.
    pub seats: Seats,
    /// When (real seconds) the session was closed and its players told; it is despawned a little later.
    pub closed_at: Option<f64>,
}

/// Which session a replicated entity or a client belongs to: replicon shows an entity to a client only
/// when both carry the same tag (and an untagged client, one not admitted, sees nothing).
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[component(immutable)]
pub struct SessionTag(pub u64);

impl VisibilityFilter for SessionTag {
    type ClientComponent = Self;
    type Scope = Entity;

    fn is_visible(&self, _client: Entity, client: Option<&Self>) -> bool {
        client == Some(self)
    }
}

/// A replicated mirror's session (despawned with it).
#[derive(Component, Clone, Copy, Debug)]
#[relationship(relationship_target = Mirrors)]
pub struct MirrorOf(pub Entity);

/// A session's replicated mirrors.
#[derive(Component, Debug, Default)]
#[relationship_target(relationship = MirrorOf, linked_spawn)]
pub struct Mirrors(Vec<Entity>);

/// The session the server was started with (`host`, tests, the demo), if any.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct HostSession(pub Option<Entity>);

/// Where the session log's lines go besides [`SessionLog::lines`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LogEcho {
    /// Nowhere (tests, sweeps).
    #[default]
    Off,
    /// Printed to stdout as they are written (the demo's live log).
    Stdout,
    /// As `tracing` events of target `session` (a hosted server: text or JSON with the rest of the log).
    Tracing,
}

/// The session's log: readable lines (kept in [`SessionLog::lines`], echoed as [`LogEcho`] says) and, when
/// echoed to `tracing`, one structured event per line (target `session`, an `event` field naming it, the
/// session's `id` — never its join code — its `round`, the game time and the `role` where there is one;
/// `--log-format json` makes each a JSON object).
#[derive(Resource, Default)]
pub struct SessionLog {
    /// Lines so far (the last [`MAX_LOG_LINES`] at most).
    pub lines: Vec<String>,
    /// Where each line also goes.
    pub echo: LogEcho,
    /// Also record debug lines (refusals).
    pub verbose: bool,
    /// The session's public id (random, hex): what log collectors group by.
    pub id: String,
    /// The round being played (set by the session as rounds start).
    pub round: u32,
}

/// The most lines a session's [`SessionLog::lines`] keeps, about four heists' worth (the oldest half goes
/// when it is full), so a session that plays on does not grow; the
/// echo (stdout, tracing) has them all.
pub const MAX_LOG_LINES: usize = 512;

/// What a log line records, for the structured log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Record<'a> {
    /// Anything else (refusals, warnings): `event = "note"`.
    Note,
    /// The session exists and waits for players.
    SessionCreated,
    /// A player was admitted.
    PlayerJoined(Role),
    /// A player closed the connection on purpose.
    PlayerLeft(Role),
    /// A player's connection was lost (their seat is kept for them).
    PlayerDropped(Role),
    /// A dropped player took their seat back.
    PlayerResumed(Role),
    /// A dropped player's seat was given up after the hold time.
    PlayerGaveUp(Role),
    /// The phase changed (not to a result).
    Phase(Phase),
    /// The round ended.
    Result {
        /// Won?
        won: bool,
        /// Why it was lost.
        reason: Option<LossReason>,
        /// The round's seed (told only now).
        seed: u64,
    },
    /// A case was broken.
    CaseBroken(&'a str),
    /// A guard radioed the others.
    GuardRadio {
        /// His name.
        guard: &'a str,
        /// `sighting` or `evidence`.
        about: &'static str,
        /// How many answer.
        answering: usize,
    },
    /// Vive picked an item up.
    ItemPicked(u16),
    /// A copy was placed on the workbench.
    Delivered(u16),
    /// Phantom judged a copy.
    Verdict {
        /// The copy.
        item: u16,
        /// Said real?
        declared_real: bool,
        /// What came of it.
        outcome: VerdictOutcome,
    },
    /// A guard's alert changed.
    GuardAlert {
        /// The guard's name.
        guard: &'a str,
        /// The new state.
        alert: GuardAlert,
    },
    /// A player asked for another round.
    RematchAsked(Role),
    /// A round began.
    RoundStarted(u32),
    /// The server began its drain: the session may finish its heist within this many seconds.
    Draining(u32),
    /// The session closed.
    SessionEnded,
}

impl SessionLog {
    /// Records a plain line stamped with game time.
    pub fn line(&mut self, t: f32, text: String) {
        self.record(t, Record::Note, text);
    }

    /// Records a line that is also a structured event.
    pub fn record(&mut self, t: f32, record: Record<'_>, text: String) {
        match self.echo {
            LogEcho::Off => {}
            LogEcho::Stdout => println!("[{t:7.2}s] {text}"),
            LogEcho::Tracing => self.trace(t, record, &text),
        }
        if self.lines.len() >= MAX_LOG_LINES {
            // A session that plays round after round must not grow without end: the oldest half goes.
            self.lines.drain(..MAX_LOG_LINES / 2);
        }
        self.lines.push(format!("[{t:7.2}s] {text}"));
    }

    fn trace(&self, t: f32, record: Record<'_>, text: &str) {
        let (id, round, time) = (self.id.as_str(), self.round, (f64::from(t) * 100.0).round() / 100.0);
        macro_rules! ev {
            ($name:literal $(, $k:ident = $v:expr)*) => {
                info!(target: "session", event = $name, session = id, round, game_time_s = time $(, $k = $v)*, "{text}")
            };
        }
        match record {
            Record::Note => ev!("note"),
            Record::SessionCreated => ev!("session_created"),
            Record::PlayerJoined(r) => ev!("player_joined", role = r.name()),
            Record::PlayerLeft(r) => ev!("player_left", role = r.name()),
            Record::PlayerDropped(r) => ev!("player_dropped", role = r.name()),
            Record::PlayerResumed(r) => ev!("player_resumed", role = r.name()),
            Record::PlayerGaveUp(r) => ev!("player_gave_up", role = r.name()),
            Record::Phase(p) => ev!("phase", phase = phase_name(p)),
            Record::Result { won, reason, seed } => {
                ev!(
                    "result",
                    won = won,
                    reason = reason.map(|r| r.to_string()).unwrap_or_default(),
                    seed = seed.to_string()
                )
            }
            Record::CaseBroken(case) => ev!("case_broken", role = Role::Vive.name(), case = case),
            Record::GuardRadio { guard, about, answering } => {
                ev!("guard_radio", guard = guard, about = about, answering = answering)
            }
            Record::ItemPicked(item) => ev!("item_picked", role = Role::Vive.name(), item = item),
            Record::Delivered(item) => ev!("delivered", role = Role::Vive.name(), item = item),
            Record::Verdict { item, declared_real, outcome } => ev!(
                "verdict",
                role = Role::Phantom.name(),
                item = item,
                declared_real = declared_real,
                outcome = format!("{outcome:?}").to_lowercase()
            ),
            Record::GuardAlert { guard, alert } => {
                ev!("guard_alert", guard = guard, alert = format!("{alert:?}").to_lowercase())
            }
            Record::RematchAsked(r) => ev!("rematch_asked", role = r.name()),
            Record::RoundStarted(n) => ev!("round_started", new_round = n),
            Record::Draining(s) => ev!("draining", within_s = s),
            Record::SessionEnded => ev!("session_ended"),
        }
    }

    /// Records a line only in verbose mode.
    pub fn debug(&mut self, t: f32, text: String) {
        if self.verbose {
            self.line(t, text);
        }
    }

    /// Describes a game event.
    pub fn event(&mut self, t: f32, game: &Game, event: &GameEvent) {
        let (record, text) = match event {
            GameEvent::PhaseChanged(p @ (Phase::Won | Phase::Lost(_))) => {
                // Only now may the seed be told: it decides which copies are real.
                let reason = if let Phase::Lost(r) = p { Some(*r) } else { None };
                (
                    Record::Result { won: *p == Phase::Won, reason, seed: game.seed },
                    format!("phase: {p:?} (seed {0}; `--seed {0}` replays this round)", game.seed),
                )
            }
            GameEvent::PhaseChanged(p) => (Record::Phase(*p), format!("phase: {p:?}")),
            GameEvent::GuardAlert { guard, alert, position } => {
                let name = game.guards.get(usize::from(guard.0)).map_or("?", |g| g.name.as_str());
                let text = format!("guard {name}: {alert:?} at ({:.1}, {:.1})", position.x, position.y);
                (Record::GuardAlert { guard: name, alert: *alert }, text)
            }
            GameEvent::Noise { kind, position, .. } => {
                if matches!(kind, heist_shared::protocol::NoiseKind::Footsteps) {
                    return; // too frequent to be worth a line
                }
                (Record::Note, format!("noise: {kind:?} at ({:.1}, {:.1})", position.x, position.y))
            }
            GameEvent::CaseBroken(c) => {
                let id = game.level.cases.get(usize::from(c.0)).map_or("?", |c| c.id.as_str());
                (Record::CaseBroken(id), format!("case {id} broken"))
            }
            GameEvent::PickedUp(i) => (Record::ItemPicked(i.0), format!("Vive picks up item #{}", i.0)),
            GameEvent::Delivered(i) => (Record::Delivered(i.0), format!("copy #{} delivered to the workbench", i.0)),
            GameEvent::Verdict { item, declared_real, outcome } => {
                let said = if *declared_real { "real" } else { "fake" };
                (
                    Record::Verdict { item: item.0, declared_real: *declared_real, outcome: *outcome },
                    format!("Phantom declares copy #{} {said}: {outcome:?}", item.0),
                )
            }
            GameEvent::Radio { guard, about, at, answering, .. } => {
                let name = |id: heist_shared::protocol::GuardId| {
                    game.guards.get(usize::from(id.0)).map_or("?", |g| g.name.as_str())
                };
                let caller = name(*guard);
                let room = game.nav.room_at(*at).and_then(|r| game.level.rooms.get(r)).map_or("?", |r| r.id.as_str());
                let what = match about {
                    heist_shared::protocol::RadioAbout::Sighting => "intruder seen",
                    heist_shared::protocol::RadioAbout::Evidence => "broken case found",
                };
                let who: Vec<&str> = answering.iter().map(|g| name(*g)).collect();
                let answer =
                    if who.is_empty() { "nobody in range".to_owned() } else { who.join(" and ") + " come to search" };
                let about = match about {
                    heist_shared::protocol::RadioAbout::Sighting => "sighting",
                    heist_shared::protocol::RadioAbout::Evidence => "evidence",
                };
                (
                    Record::GuardRadio { guard: caller, about, answering: answering.len() },
                    format!("guard {caller} radios: {what} in the {room} at ({:.1}, {:.1}); {answer}", at.x, at.y),
                )
            }
            GameEvent::Alarm(level) => (Record::Note, format!("alarm level {level}")),
            GameEvent::Warning(w) => (Record::Note, format!("Phantom warns Vive: {w:?}")),
            GameEvent::WarningSeen(w) => (Record::Note, format!("Vive's client shows the warning: {w:?}")),
            GameEvent::Joined(role) => (Record::PlayerJoined(*role), format!("{role} joined")),
            GameEvent::Left { role, dropped: false } => (Record::PlayerLeft(*role), format!("{role} left")),
            GameEvent::Left { role, dropped: true } => {
                (Record::PlayerDropped(*role), format!("{role} dropped (connection lost): the seat is kept for them"))
            }
            GameEvent::Resumed(role) => (Record::PlayerResumed(*role), format!("{role} is back (seat taken back)")),
            GameEvent::GaveUp(role) => {
                (Record::PlayerGaveUp(*role), format!("{role} did not come back: the seat is given up"))
            }
            GameEvent::RematchAsked(role) => (Record::RematchAsked(*role), format!("{role} asks for another round")),
            GameEvent::RoundStarted(n) => {
                self.round = *n;
                (Record::RoundStarted(*n), format!("round {n} begins"))
            }
            GameEvent::EndingSoon(s) => (Record::Note, format!("the session ends in {s} s unless a round begins")),
            GameEvent::ServerClosing { within_s } => (
                Record::Draining(*within_s),
                format!("the server is shutting down: a heist under way may finish within {within_s} s"),
            ),
        };
        self.record(t, record, text);
    }
}

fn phase_name(phase: Phase) -> &'static str {
    match phase {
        Phase::Lobby => "lobby",
        Phase::Heist => "heist",
        Phase::Won => "won",
        Phase::Lost(_) => "lost",
    }
}

/// Marks a replicated mirror of a session: a few entities a session, whatever its number of objects
/// (replication walks entities × clients; docs/decisions.md).
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mirror {
    /// The session's state ([`SessionView`]).
    Session,
    /// Vive.
    Vive,
    /// Phantom's tool.
    Tool,
    /// Every display case and item ([`Cases`], [`Items`]).
    Objects,
    /// The guards Vive could see or hear now, for Vive alone ([`Guards`]).
    GuardsPerceived,
    /// Every guard, for Phantom alone.
    GuardsAll,
}

/// System sets of the session.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum SessionSystems {
    /// `FixedUpdate`: advance the game by one fixed step.
    Step,
    /// `PostUpdate`, before the network send: mirror game state into replicated components.
    Mirror,
}

/// Runs the games and mirrors them.
pub struct SessionPlugin;

impl Plugin for SessionPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<HostSession>()
            .add_visibility_filter::<SessionTag>()
            .add_systems(FixedUpdate, step_games.in_set(SessionSystems::Step))
            .add_systems(PostUpdate, mirror_games.in_set(SessionSystems::Mirror));
    }
}

fn step_games(mut sessions: Query<&mut Session>, time: Res<Time>) {
    let dt = time.delta_secs();
    for mut session in &mut sessions {
        session.game.step(dt);
    }
}

/// `RESULT: Won` or `RESULT: Lost(<reason>)` once the session has ended.
pub fn result_line(game: &Game) -> Option<String> {
    match game.phase {
        Phase::Won => Some("RESULT: Won".into()),
        Phase::Lost(reason) => Some(format!("RESULT: Lost({reason})")),
        _ => None,
    }
}

/// Spawns `session` and its replicated mirrors; returns the session's entity.
pub fn spawn_session(commands: &mut Commands, session: Session) -> Entity {
    let tag = SessionTag(session.id);
    let g = &session.game;
    let both = (Replicated, Audience::Both, tag);
    let perceived = Guards((0..g.guards.len()).filter(|i| g.vive_perceives(*i)).map(|i| guard_view(g, i)).collect());
    let all = Guards((0..g.guards.len()).map(|i| guard_view(g, i)).collect());
    let mirrors = [
        commands.spawn((both, Mirror::Session, session_view(g))).id(),
        commands.spawn((both, Mirror::Vive, vive_view(g))).id(),
        commands.spawn((both, Mirror::Tool, g.tool)).id(),
        commands.spawn((both, Mirror::Objects, cases(g), items(g))).id(),
        commands.spawn((Replicated, Audience::Only(Role::Vive), tag, Mirror::GuardsPerceived, perceived)).id(),
        commands.spawn((Replicated, Audience::Only(Role::Phantom), tag, Mirror::GuardsAll, all)).id(),
    ];
    let entity = commands.spawn((session, tag)).id();
    for mirror in mirrors {
        commands.entity(mirror).insert(MirrorOf(entity));
    }
    entity
}

/// Brings every session's mirrors up to date. A mirror is compared with the game in place and written
/// (and so replicated) only when it differs: no allocation for a session where nothing changed.
#[allow(clippy::type_complexity)]
fn mirror_games(
    sessions: Query<(&Session, &Mirrors)>,
    mut mirrors: Query<(
        &Mirror,
        AnyOf<(&mut SessionView, &mut ViveAvatar, &mut PhantomTool, &mut Cases, &mut Items, &mut Guards)>,
    )>,
) {
    for (session, of) in &sessions {
        let g = &session.game;
        // Which guards Vive perceives, worked out once a tick (line of sight, hearing are not cheap): bit
        // `i` for guard `i`; a level with more than 64 guards asks again for the rest.
        let bits = (0..g.guards.len().min(64)).filter(|i| g.vive_perceives(*i)).fold(0u64, |m, i| m | 1 << i);
        let perceived = |i: usize| if i < 64 { bits & (1 << i) != 0 } else { g.vive_perceives(i) };
        let mut iter = mirrors.iter_many_mut(of.iter());
        while let Some((mirror, views)) = iter.fetch_next() {
            match (*mirror, views) {
                (Mirror::Session, (Some(v), ..)) => sync_session_view(v, g),
                (Mirror::Vive, (_, Some(v), ..)) => sync_vive_view(v, g),
                (Mirror::Tool, (_, _, Some(mut v), ..)) => {
                    v.set_if_neq(g.tool);
                }
                (Mirror::Objects, (_, _, _, Some(mut c), Some(mut i), _)) => {
                    if !cases_are(&c.0, g) {
                        *c = cases(g);
                    }
                    if !items_are(&i.0, g) {
                        *i = items(g);
                    }
                }
                (Mirror::GuardsPerceived, (.., Some(v))) => sync_guards(v, g, perceived),
                (Mirror::GuardsAll, (.., Some(v))) => sync_guards(v, g, |_| true),
                _ => {}
            }
        }
    }
}

/// Brings the session's view up to date in place (its time left changes every tick of a heist).
fn sync_session_view(mut v: Mut<SessionView>, g: &Game) {
    let same_targets =
        v.targets.len() == g.targets.len() && v.targets.iter().zip(&g.targets).all(|(v, t)| *v == (t.kind, t.secured));
    if v.phase == g.phase
        && v.time_left_s == g.time_left_s
        && v.alarm == g.alarm
        && v.present == g.present
        && v.difficulty == g.difficulty
        && same_targets
    {
        return;
    }
    let v = &mut *v;
    (v.phase, v.time_left_s, v.alarm, v.present, v.difficulty) =
        (g.phase, g.time_left_s, g.alarm, g.present, g.difficulty);
    if !same_targets {
        v.targets = g.targets.iter().map(|t| (t.kind, t.secured)).collect();
    }
}

/// Brings Vive's view up to date in place (he moves most ticks; what he carries rarely changes).
fn sync_vive_view(mut v: Mut<ViveAvatar>, g: &Game) {
    let vive = &g.vive;
    if v.position == vive.position
        && v.velocity == vive.velocity
        && v.facing == vive.facing
        && v.stance == vive.stance
        && v.carrying == vive.carrying
        && v.last_input_seq == vive.last_input_seq
    {
        return;
    }
    let v = &mut *v;
    (v.position, v.velocity, v.facing, v.stance, v.last_input_seq) =
        (vive.position, vive.velocity, vive.facing, vive.stance, vive.last_input_seq);
    if v.carrying != vive.carrying {
        v.carrying.clone_from(&vive.carrying);
    }
}

fn cases(g: &Game) -> Cases {
    Cases((0..g.cases.len()).map(|i| case_view(g, i)).collect())
}

fn cases_are(v: &[CaseView], g: &Game) -> bool {
    v.len() == g.cases.len() && v.iter().enumerate().all(|(i, c)| *c == case_view(g, i))
}

fn items(g: &Game) -> Items {
    Items((0..g.items.len()).map(|i| item_view(g, i)).collect())
}

fn items_are(v: &[ItemView], g: &Game) -> bool {
    v.len() == g.items.len()
        && v.iter()
            .zip(&g.items)
            .enumerate()
            .all(|(i, (v, item))| v.id == ItemId(i as u16) && v.place == item.place && v.kind == item.kind)
}

/// Brings `list` to the guards `shown` picks, as the game has them now: moved in place while the same
/// guards are listed (no allocation: guards move every tick), rebuilt when one comes or goes.
fn sync_guards(mut list: Mut<Guards>, g: &Game, shown: impl Fn(usize) -> bool + Copy) {
    let picked = || g.guards.iter().enumerate().filter(move |(i, _)| shown(*i)).map(|(_, guard)| guard);
    let same_guards =
        list.0.len() == picked().count() && list.0.iter().zip(picked()).all(|(v, guard)| v.id == guard.id);
    if !same_guards {
        list.0 = picked().map(guard_view_of).collect();
        return;
    }
    let moved = list.0.iter().zip(picked()).any(|(v, guard)| {
        v.position != guard.position || v.facing != guard.facing || v.alert != guard.alert || v.name != guard.name
    });
    if moved {
        for (v, guard) in list.0.iter_mut().zip(picked()) {
            v.position = guard.position;
            v.facing = guard.facing;
            v.alert = guard.alert;
            if v.name != guard.name {
                v.name.clone_from(&guard.name);
            }
        }
    }
}

fn session_view(g: &Game) -> SessionView {
    SessionView {
        phase: g.phase,
        time_left_s: g.time_left_s,
        alarm: g.alarm,
        targets: g.targets.iter().map(|t| (t.kind, t.secured)).collect(),
        present: g.present,
        difficulty: g.difficulty,
    }
}

fn vive_view(g: &Game) -> ViveAvatar {
    ViveAvatar {
        position: g.vive.position,
        velocity: g.vive.velocity,
        facing: g.vive.facing,
        stance: g.vive.stance,
        carrying: g.vive.carrying.clone(),
        last_input_seq: g.vive.last_input_seq,
    }
}

fn guard_view(g: &Game, i: usize) -> GuardView {
    guard_view_of(&g.guards[i])
}

fn guard_view_of(guard: &crate::game::Guard) -> GuardView {
    GuardView {
        id: guard.id,
        name: guard.name.clone(),
        position: guard.position,
        facing: guard.facing,
        alert: guard.alert,
    }
}

fn case_view(g: &Game, i: usize) -> CaseView {
    CaseView { id: CaseId(i as u16), position: g.cases[i].position, broken: g.cases[i].broken }
}

fn item_view(g: &Game, i: usize) -> ItemView {
    let item = &g.items[i];
    ItemView { id: ItemId(i as u16), kind: item.kind.clone(), place: item.place }
}

#[cfg(test)]
mod tests {
    use std::io::Write;
    use std::sync::{Arc, Mutex};

    use heist_shared::level::Level;
    use heist_shared::protocol::{CaseId, GuardId, ItemId};

    use super::*;
    use crate::game::GameOptions;

    /// Collects what the subscriber writes.
    #[derive(Clone, Default)]
    struct Captured(Arc<Mutex<Vec<u8>>>);

    impl Write for Captured {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.0.lock().map_err(|_| std::io::Error::other("poisoned"))?.extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// The session's events as `--log-format json` writes them, parsed back.
    fn json_lines(write: impl FnOnce()) -> Vec<serde_json::Value> {
        let captured = Captured::default();
        let sink = captured.clone();
        let subscriber = tracing_subscriber::fmt()
            .json()
            .flatten_event(true)
            .with_writer(move || sink.clone())
            .with_max_level(bevy::log::tracing::Level::INFO)
            .finish();
        bevy::log::tracing::subscriber::with_default(subscriber, write);
        let bytes = captured.0.lock().map(|b| b.clone()).unwrap_or_default();
        String::from_utf8_lossy(&bytes)
            .lines()
            .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("not JSON ({e}): {l}")))
            .collect()
    }

    #[test]
    fn a_long_lived_sessions_log_keeps_its_latest_lines_within_the_bound() {
        let mut log = SessionLog::default();
        for n in 0..(3 * MAX_LOG_LINES) {
            log.line(n as f32, format!("line {n}"));
            assert!(log.lines.len() <= MAX_LOG_LINES, "{} lines after {n}", log.lines.len());
        }
        assert!(log.lines.last().is_some_and(|l| l.ends_with(&format!("line {}", 3 * MAX_LOG_LINES - 1))));
        assert!(log.lines.len() >= MAX_LOG_LINES / 2, "the latest half at least is kept");
    }

    #[test]
    fn every_session_event_is_one_json_object_naming_the_event_session_and_role() {
        // A seed of many digits: a short one can turn up inside a timestamp.
        let game = Game::new(Level::museum(), &GameOptions { seed: 8_675_309_421_337, ..Default::default() });
        let mut log = SessionLog { echo: LogEcho::Tracing, id: "0badc0de".into(), round: 1, ..Default::default() };
        let lines = json_lines(|| {
            log.record(0.0, Record::SessionCreated, "session created".into());
            for event in [
                GameEvent::Joined(Role::Phantom),
                GameEvent::Left { role: Role::Vive, dropped: true },
                GameEvent::Left { role: Role::Vive, dropped: false },
                GameEvent::PhaseChanged(Phase::Heist),
                GameEvent::CaseBroken(CaseId(0)),
                GameEvent::PickedUp(ItemId(3)),
                GameEvent::Delivered(ItemId(3)),
                GameEvent::Verdict { item: ItemId(3), declared_real: true, outcome: VerdictOutcome::Secured },
                GameEvent::GuardAlert { guard: GuardId(0), alert: GuardAlert::Chasing, position: Default::default() },
                GameEvent::PhaseChanged(Phase::Lost(LossReason::Caught)),
                GameEvent::RematchAsked(Role::Vive),
                GameEvent::RoundStarted(2),
                GameEvent::Resumed(Role::Phantom),
                GameEvent::GaveUp(Role::Vive),
            ] {
                log.event(12.5, &game, &event);
            }
        });
        let names: Vec<&str> = lines.iter().map(|l| l["event"].as_str().unwrap_or("?")).collect();
        assert_eq!(
            names,
            [
                "session_created",
                "player_joined",
                "player_dropped",
                "player_left",
                "phase",
                "case_broken",
                "item_picked",
                "delivered",
                "verdict",
                "guard_alert",
                "result",
                "rematch_asked",
                "round_started",
                "player_resumed",
                "player_gave_up"
            ]
        );
        for line in &lines {
            assert_eq!(line["session"], "0badc0de", "{line}");
            assert_eq!(line["target"], "session");
            assert!(line["message"].is_string());
            assert!(!line.to_string().contains(&game.seed.to_string()) || line["event"] == "result", "{line}");
        }
        assert_eq!(lines[1]["role"], "phantom");
        assert_eq!(lines[2]["role"], "vive");
        assert_eq!(lines[4]["phase"], "heist");
        assert_eq!(lines[5]["case"], game.level.cases[0].id.as_str());
        assert_eq!((lines[8]["outcome"].as_str(), lines[8]["role"].as_str()), (Some("secured"), Some("phantom")));
        assert_eq!(lines[9]["alert"], "chasing");
        assert_eq!((lines[13]["role"].as_str(), lines[14]["role"].as_str()), (Some("phantom"), Some("vive")));
        assert_eq!((lines[10]["won"].as_bool(), lines[10]["reason"].as_str()), (Some(false), Some("caught")));
        assert_eq!(
            lines[10]["seed"], "8675309421337",
            "the seed is told once the round is over (a string: it is 64 bits)"
        );
        assert_eq!(lines[10]["game_time_s"], 12.5);
        assert_eq!(lines[12]["new_round"], 2);
    }
}
