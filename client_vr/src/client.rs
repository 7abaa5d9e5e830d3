//! The Vive client's game logic, the same with or without rendering: session state, prediction and
//! reconciliation of the body, interpolation of what the server moves, events, and the end of the game.
//!
//! Data flow per frame: before the fixed-step loop (`RunFixedMainLoop`), [`ViveSystems::Receive`] (level,
//! session, server state → predictor, snapshots, [`Happened`] events) → intents (`IntentSystems::Clear`,
//! `Gather` from XR / desktop / bot); in `FixedUpdate` (60 Hz, the server's tick) `IntentSystems::Send`
//! sends one movement input and predicts it; in `Update`, [`ViveSystems::Present`] (world, HUD, sound,
//! controller pulses; only what the mode added).

use bevy::app::AppExit;
use bevy::app::RunFixedMainLoopSystems;
use bevy::prelude::*;
use glam::{Quat, Vec2};
use heist_client::Inbox;
use heist_shared::level::WallSet;
use heist_shared::protocol::{GameEvent, GuardView, PhantomTool, Phase, Role, SessionView, TICK_HZ, ViveAvatar};

pub use crate::state::{PulseReason, ViveState};

use crate::intent::{self, InputSource, Intent, IntentSystems, Sent};
use crate::interp::{Snapshot, Track};
use crate::predict::Predictor;
use crate::space;

/// How the client runs.
#[derive(Resource, Clone, Debug)]
pub struct ViveSettings {
    /// Which input drives the player.
    pub input: InputSource,
    /// Say ready as soon as the level arrives (players press Enter or the trigger instead).
    pub ready_at_once: bool,
    /// Quit this many seconds after the heist ends (None: stay).
    pub quit_after_end_s: Option<f32>,
}

impl Default for ViveSettings {
    fn default() -> Self {
        Self { input: InputSource::Desktop, ready_at_once: false, quit_after_end_s: None }
    }
}

/// A game event from the server, for the presentation systems.
#[derive(Message, Clone, Debug)]
pub struct Happened(pub GameEvent);

/// A controller pulse (XR plays it on the hand; elsewhere it is counted).
#[derive(Message, Clone, Copy, Debug, PartialEq)]
pub struct Pulse {
    /// Strength 0..1.
    pub amplitude: f32,
    /// Duration, seconds.
    pub seconds: f32,
    /// Why (for the log and tests).
    pub why: PulseReason,
}

/// System sets of the Vive client.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum ViveSystems {
    /// Server state in (`RunFixedMainLoop`, before the fixed step).
    Receive,
    /// World, HUD, sound, pulses (`Update`).
    Present,
}

/// The Vive client's logic (see the module docs).
pub struct ViveClientPlugin {
    /// Settings.
    pub settings: ViveSettings,
}

impl Plugin for ViveClientPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(self.settings.clone())
            .insert_resource(self.settings.input)
            .init_resource::<ViveState>()
            .init_resource::<Intent>()
            .init_resource::<Sent>()
            .add_message::<Happened>()
            .add_message::<Pulse>()
            // One movement input per server tick, whatever the frame rate: the server applies each for
            // exactly one tick, so the prediction repeats its arithmetic.
            .insert_resource(Time::<Fixed>::from_hz(TICK_HZ))
            .configure_sets(
                RunFixedMainLoop,
                (ViveSystems::Receive, IntentSystems::Clear, IntentSystems::Gather)
                    .chain()
                    .in_set(RunFixedMainLoopSystems::BeforeFixedMainLoop),
            )
            .add_systems(
                RunFixedMainLoop,
                (take_level, track_session, reconcile, snapshots, events, tell_the_link)
                    .chain()
                    .in_set(ViveSystems::Receive),
            )
            .add_systems(RunFixedMainLoop, intent::clear.in_set(IntentSystems::Clear))
            .add_systems(RunFixedMainLoop, ready_at_once.in_set(IntentSystems::Gather))
            .add_systems(FixedUpdate, intent::send.in_set(IntentSystems::Send))
            .add_systems(Update, (settle, pulses, count_pulses, quit_after_end).chain().in_set(ViveSystems::Present));
        if self.settings.input == InputSource::Bot {
            app.add_plugins(crate::bot::BotInputPlugin);
        }
    }
}

fn take_level(inbox: Res<Inbox>, mut state: ResMut<ViveState>, time: Res<Time>) {
    if state.level.is_some() {
        return;
    }
    let Some(level) = inbox.level.clone() else { return };
    let walls = WallSet::new(&level);
    state.predictor = Some(Predictor::new(walls.clone(), level.vive_spawn));
    let now = time.elapsed_secs_f64();
    state
        .say(now, format!("Joined {} as Vive: {} rooms, {} guards", level.name, level.rooms.len(), level.guards.len()));
    state.walls = Some(walls);
    state.level = Some(level);
}

fn track_session(q: Query<&SessionView>, mut state: ResMut<ViveState>, time: Res<Time>) {
    let Ok(session) = q.single() else { return };
    state.time_left_s = session.time_left_s;
    state.alarm = session.alarm;
    if session.phase != state.phase {
        let now = time.elapsed_secs_f64();
        let text = match session.phase {
            Phase::Lobby => "In the lobby".to_owned(),
            Phase::Heist => "The heist is on".to_owned(),
            Phase::Won => "RESULT: won. Enter (or a trigger) asks for another round".to_owned(),
            Phase::Lost(why) => format!("RESULT: lost ({why}). Enter (or a trigger) asks for another round"),
        };
        if session.phase == Phase::Heist {
            state.ended_s = 0.0;
        }
        state.phase = session.phase;
        state.say(now, text);
    }
    if matches!(session.phase, Phase::Won | Phase::Lost(_)) {
        state.ended_s += time.delta_secs();
    }
}

/// The server's state of the body reconciles the prediction.
fn reconcile(q: Query<&ViveAvatar, Changed<ViveAvatar>>, mut state: ResMut<ViveState>) {
    let Ok(avatar) = q.single() else { return };
    let in_heist = state.phase == Phase::Heist;
    state.carrying.clone_from(&avatar.carrying);
    let Some(p) = state.predictor.as_mut() else { return };
    if !in_heist || avatar.last_input_seq == 0 {
        // Nothing of ours applied yet: the server's position is the truth.
        p.reset(avatar.position);
    } else {
        p.reconcile(avatar.position, avatar.last_input_seq);
    }
    state.reconciliations += 1;
}

/// Guards and the Phantom's tool get a snapshot on every update.
fn snapshots(
    mut commands: Commands,
    time: Res<Time>,
    state: Res<ViveState>,
    mut guards: Query<(Entity, &GuardView, Option<&mut Track>), (Changed<GuardView>, Without<PhantomTool>)>,
    mut tool: Query<(Entity, &PhantomTool, Option<&mut Track>), Changed<PhantomTool>>,
) {
    let t = time.elapsed_secs_f64();
    // The first snapshot of an entity starts its track.
    let mut record = |e: Entity, track: Option<Mut<Track>>, s: Snapshot| match track {
        Some(mut track) => track.push(s),
        None => {
            let mut track = Track::default();
            track.push(s);
            commands.entity(e).insert(track);
        }
    };
    for (e, g, track) in &mut guards {
        record(e, track, Snapshot { t, position: space::world(g.position, 0.0), rotation: space::rotation(g.facing) });
    }
    let bench = state.level.as_ref().map_or(Vec2::ZERO, |l| l.workbench);
    for (e, tool, track) in &mut tool {
        let position = space::world(bench, space::BENCH_TOP_M + 0.15) + tool.position;
        let rotation = if tool.rotation.is_finite() { tool.rotation.normalize() } else { Quat::IDENTITY };
        record(e, track, Snapshot { t, position, rotation });
    }
}

/// Server events become [`Happened`] messages and HUD lines; glass near the body pulses the hand.
fn events(
    mut inbox: ResMut<Inbox>,
    mut out: MessageWriter<Happened>,
    mut pulses: MessageWriter<Pulse>,
    mut state: ResMut<ViveState>,
    mut sent: ResMut<crate::intent::Sent>,
    time: Res<Time>,
) {
    let now = time.elapsed_secs_f64();
    for e in std::mem::take(&mut inbox.events) {
        if let GameEvent::Noise { kind: heist_shared::protocol::NoiseKind::Glass, position, .. } = &e
            && state.body().is_some_and(|b| b.distance(*position) < heist_shared::rules::REACH * 2.0)
        {
            pulses.write(Pulse { amplitude: 1.0, seconds: 0.15, why: PulseReason::Glass });
        }
        if let Some(line) = hud_line(&e, state.level.as_ref()) {
            state.say(now, line);
        }
        out.write(Happened(e));
    }
    for r in std::mem::take(&mut inbox.refusals) {
        sent.refused();
        state.say(now, format!("The server refused: {r:?}"));
    }
}

/// The HUD's line for a server event, if it gets one (guards and rooms named from `level`).
pub fn hud_line(e: &GameEvent, level: Option<&heist_shared::level::Level>) -> Option<String> {
    let guard_name = |id: u16| {
        level.and_then(|l| l.guards.get(usize::from(id))).map_or_else(|| format!("Guard {id}"), |g| g.name.clone())
    };
    match e {
        GameEvent::CaseBroken(c) => Some(format!("Case {} shattered", c.0)),
        GameEvent::Delivered(i) => Some(format!("Copy {} on the workbench", i.0)),
        GameEvent::Verdict { outcome, .. } => Some(format!("Phantom's verdict: {outcome:?}")),
        GameEvent::Alarm(n) => Some(format!("ALARM level {n}")),
        // The client core has told Phantom it arrived.
        GameEvent::Warning(w) => Some(format!("Phantom warns: {w:?}")),
        GameEvent::WarningSeen(_) => None,
        GameEvent::GuardAlert { guard, alert, .. } => {
            Some(format!("{} is {}", guard_name(guard.0), format!("{alert:?}").to_lowercase()))
        }
        GameEvent::Radio { guard, about, at, .. } => {
            let room = level
                .and_then(|l| l.rooms.iter().find(|r| r.contains(*at, 0.0)))
                .map_or_else(|| "museum".into(), |r| r.id.replace('_', " "));
            let what = match about {
                heist_shared::protocol::RadioAbout::Sighting => "intruder seen",
                heist_shared::protocol::RadioAbout::Evidence => "broken case found",
            };
            Some(format!("RADIO {}: {what} in the {room}", guard_name(guard.0)))
        }
        GameEvent::Noise { .. } | GameEvent::PhaseChanged(_) | GameEvent::PickedUp(_) => None,
        GameEvent::Joined(_)
        | GameEvent::Left { .. }
        | GameEvent::Resumed(_)
        | GameEvent::GaveUp(_)
        | GameEvent::RematchAsked(_)
        | GameEvent::RoundStarted(_)
        | GameEvent::EndingSoon(_)
        | GameEvent::ServerClosing { .. } => heist_client::notice::session_notice(e, Role::Vive),
    }
}

/// The connection's changes on the HUD: lost after 3 s of silence, back, gone, trying to get back in or
/// giving up; and why the server let us go.
fn tell_the_link(
    link: Res<heist_client::Link>,
    inbox: Res<Inbox>,
    leaving: Res<heist_client::Leaving>,
    reconnect: Res<heist_client::Reconnect>,
    mut news: Local<heist_client::notice::LinkNews>,
    mut state: ResMut<ViveState>,
    time: Res<Time>,
) {
    let now = time.elapsed_secs_f64();
    for line in news.news(*link, &inbox, &leaving, &reconnect) {
        state.say(now, line);
    }
}

/// A new item in the hands pulses the controller.
fn pulses(mut state: ResMut<ViveState>, mut out: MessageWriter<Pulse>, mut last: Local<usize>) {
    let n = state.carrying.len();
    if n > *last {
        out.write(Pulse { amplitude: 0.6, seconds: 0.05, why: PulseReason::Grab });
    }
    *last = n;
    state.carrying.dedup();
}

fn count_pulses(mut pulses: MessageReader<Pulse>, mut state: ResMut<ViveState>) {
    for p in pulses.read() {
        state.pulses.push(p.why);
    }
}

fn settle(mut state: ResMut<ViveState>, time: Res<Time>) {
    let dt = time.delta_secs();
    if let Some(p) = state.predictor.as_mut() {
        p.settle(dt);
    }
}

fn ready_at_once(
    settings: Res<ViveSettings>,
    state: Res<ViveState>,
    mut intent: ResMut<Intent>,
    mut done: Local<bool>,
) {
    if settings.ready_at_once && !*done && state.level.is_some() && state.phase == Phase::Lobby {
        intent.actions.push(intent::Action::Ready);
        *done = true;
    }
}

fn quit_after_end(
    settings: Res<ViveSettings>,
    state: Res<ViveState>,
    mut exit: MessageWriter<AppExit>,
    inbox: Res<Inbox>,
    link: Res<heist_client::Link>,
    reconnect: Res<heist_client::Reconnect>,
) {
    if let Some(after) = settings.quit_after_end_s
        && (state.ended_s > after || heist_client::connection_over(*link, &inbox, &reconnect))
    {
        exit.write(AppExit::Success);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::level::Level;
    use heist_shared::protocol::{GuardAlert, GuardId, RadioAbout};

    #[test]
    fn a_guards_alert_names_him_and_a_radio_call_names_the_room_it_is_about() {
        let level = Level::museum();
        let (guard, room) = (&level.guards[0], &level.rooms[1]);
        let alert = GameEvent::GuardAlert { guard: GuardId(0), alert: GuardAlert::Chasing, position: Vec2::ZERO };
        assert_eq!(hud_line(&alert, Some(&level)), Some(format!("{} is chasing", guard.name)));
        let radio = GameEvent::Radio {
            guard: GuardId(0),
            about: RadioAbout::Evidence,
            at: room.centre(),
            from: Vec2::ZERO,
            answering: Vec::new(),
        };
        let line = hud_line(&radio, Some(&level)).expect("a radio call is shown");
        assert_eq!(line, format!("RADIO {}: broken case found in the {}", guard.name, room.id.replace('_', " ")));
        assert_eq!(hud_line(&alert, None), Some("Guard 0 is chasing".into()), "before the level: by number");
    }

    #[test]
    fn noises_and_phase_changes_are_not_written_on_the_hud() {
        let glass =
            GameEvent::Noise { kind: heist_shared::protocol::NoiseKind::Glass, position: Vec2::ZERO, loudness: 16.0 };
        assert_eq!(hud_line(&glass, None), None);
        assert_eq!(hud_line(&GameEvent::PhaseChanged(heist_shared::protocol::Phase::Heist), None), None);
        assert_eq!(hud_line(&GameEvent::Alarm(2), None), Some("ALARM level 2".into()));
    }
}
