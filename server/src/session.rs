//! The session in the ECS: the [`Game`] as a resource stepped in `FixedUpdate`, its state mirrored
//! into replicated entities in `PostUpdate`, and a readable log of what happened.

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use heist_shared::protocol::{
    Audience, CaseId, CaseView, GameEvent, GuardView, ItemId, ItemView, PhantomTool, Phase, SessionView, ViveAvatar,
};

use crate::game::Game;
use crate::net::NetSystems;

/// The authoritative game.
#[derive(Resource)]
pub struct GameState(pub Game);

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

/// Human-readable log of the session.
#[derive(Resource, Default)]
pub struct SessionLog {
    /// Lines so far.
    pub lines: Vec<String>,
    /// Where each line also goes.
    pub echo: LogEcho,
    /// Also record debug lines (refusals).
    pub verbose: bool,
}

impl SessionLog {
    /// Records a line stamped with game time.
    pub fn line(&mut self, t: f32, text: String) {
        match self.echo {
            LogEcho::Off => {}
            LogEcho::Stdout => println!("[{t:7.2}s] {text}"),
            LogEcho::Tracing => {
                info!(target: "session", game_time_s = (f64::from(t) * 100.0).round() / 100.0, "{text}")
            }
        }
        self.lines.push(format!("[{t:7.2}s] {text}"));
    }

    /// Records a line only in verbose mode.
    pub fn debug(&mut self, t: f32, text: String) {
        if self.verbose {
            self.line(t, text);
        }
    }

    /// Describes a game event.
    pub fn event(&mut self, t: f32, game: &Game, event: &GameEvent) {
        let text = match event {
            GameEvent::PhaseChanged(p @ (Phase::Won | Phase::Lost(_))) => {
                // Only now may the seed be told: it decides which copies are real.
                format!("phase: {p:?} (seed {0}; `--seed {0}` replays this session)", game.seed)
            }
            GameEvent::PhaseChanged(p) => format!("phase: {p:?}"),
            GameEvent::GuardAlert { guard, alert, position } => {
                let name = game.guards.get(usize::from(guard.0)).map_or("?", |g| g.name.as_str());
                format!("guard {name}: {alert:?} at ({:.1}, {:.1})", position.x, position.y)
            }
            GameEvent::Noise { kind, position, .. } => {
                if matches!(kind, heist_shared::protocol::NoiseKind::Footsteps) {
                    return; // too frequent to be worth a line
                }
                format!("noise: {kind:?} at ({:.1}, {:.1})", position.x, position.y)
            }
            GameEvent::CaseBroken(c) => {
                format!("case {} broken", game.level.cases.get(usize::from(c.0)).map_or("?", |c| c.id.as_str()))
            }
            GameEvent::Delivered(i) => format!("copy #{} delivered to the workbench", i.0),
            GameEvent::Verdict { item, declared_real, outcome } => {
                let said = if *declared_real { "real" } else { "fake" };
                format!("Phantom declares copy #{} {said}: {outcome:?}", item.0)
            }
            GameEvent::Alarm(level) => format!("alarm level {level}"),
            GameEvent::Warning(w) => format!("Phantom warns Vive: {w:?}"),
        };
        self.line(t, text);
    }
}

/// Marks the replicated mirror of a game object.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mirror {
    /// The session entity.
    Session,
    /// Vive.
    Vive,
    /// Guard by index.
    Guard(usize),
    /// Case by index.
    Case(usize),
    /// Item by index.
    Item(usize),
}

/// System sets of the session.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum SessionSystems {
    /// `FixedUpdate`: advance the game by one fixed step.
    Step,
    /// `PostUpdate`, before the network send: mirror game state into replicated components.
    Mirror,
}

/// Runs the game and mirrors it.
pub struct SessionPlugin;

impl Plugin for SessionPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<SessionLog>()
            .configure_sets(PostUpdate, SessionSystems::Mirror.before(NetSystems::Send))
            .add_systems(Startup, spawn_mirrors)
            .add_systems(FixedUpdate, step_game.in_set(SessionSystems::Step))
            .add_systems(PostUpdate, mirror_game.in_set(SessionSystems::Mirror));
    }
}

fn step_game(mut game: ResMut<GameState>, time: Res<Time>) {
    game.0.step(time.delta_secs());
}

/// `RESULT: Won` or `RESULT: Lost(<reason>)` once the session has ended.
pub fn result_line(game: &Game) -> Option<String> {
    match game.phase {
        Phase::Won => Some("RESULT: Won".into()),
        Phase::Lost(reason) => Some(format!("RESULT: Lost({reason})")),
        _ => None,
    }
}

fn spawn_mirrors(mut commands: Commands, game: Res<GameState>) {
    let g = &game.0;
    let both = (Replicated, Audience::Both);
    commands.spawn((both, Mirror::Session, session_view(g)));
    commands.spawn((both, Mirror::Vive, vive_view(g)));
    commands.spawn((both, g.tool));
    for i in 0..g.guards.len() {
        commands.spawn((both, Mirror::Guard(i), guard_view(g, i)));
    }
    for i in 0..g.cases.len() {
        commands.spawn((both, Mirror::Case(i), case_view(g, i)));
    }
    for i in 0..g.items.len() {
        commands.spawn((both, Mirror::Item(i), item_view(g, i)));
    }
}

#[allow(clippy::type_complexity)]
fn mirror_game(
    game: Res<GameState>,
    mut session: Query<&mut SessionView>,
    mut vive: Query<&mut ViveAvatar>,
    mut guards: Query<(&Mirror, &mut GuardView)>,
    mut cases: Query<(&Mirror, &mut CaseView)>,
    mut items: Query<(&Mirror, &mut ItemView)>,
    mut tool: Query<&mut PhantomTool>,
) {
    let g = &game.0;
    for mut s in &mut session {
        s.set_if_neq(session_view(g));
    }
    for mut v in &mut vive {
        v.set_if_neq(vive_view(g));
    }
    for mut t in &mut tool {
        t.set_if_neq(g.tool);
    }
    for (m, mut v) in &mut guards {
        if let Mirror::Guard(i) = *m {
            v.set_if_neq(guard_view(g, i));
        }
    }
    for (m, mut v) in &mut cases {
        if let Mirror::Case(i) = *m {
            v.set_if_neq(case_view(g, i));
        }
    }
    for (m, mut v) in &mut items {
        if let Mirror::Item(i) = *m {
            v.set_if_neq(item_view(g, i));
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
    let guard = &g.guards[i];
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
