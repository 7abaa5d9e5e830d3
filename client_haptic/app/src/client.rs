//! The Phantom client as a Bevy app: the session (through the shared client core), the copy on the
//! workbench, verdicts, speech, sounds, keys, and the touch bot.
//!
//! You need this module to run Phantom. [`start`] opens the device, the haptic loop and the audio engine
//! (they can fail, so they are set up before the plugin) and adds [`PhantomClientPlugin`]. Systems run in
//! [`PhantomSystems`] order each frame: `Receive` (server events and copies in), `Play` (lobby; the keys
//! and the device's buttons read, decided on (`input`) and acted on; verdicts, the bot), `Sound` (speech,
//! museum sounds, contact sound); all in `Update`. What the client remembers is in `state`, one
//! resource for each job.

use std::collections::HashMap;

use bevy::prelude::*;
use heist_client::Inbox;
use heist_shared::artifact::{ArtifactKind, MaterialClass};
use heist_shared::protocol::{
    ClientMsg, GameEvent, GuardAlert, GuardView, ItemId, ItemKind, ItemView, LobbyMsg, PhantomMsg, Phase, Role,
    SessionView, VerdictOutcome, ViveAvatar,
};

pub use crate::schedule::{HeistEvent, PhantomSystems};
pub use crate::state::{HandSteering, Menu, VerdictRecord, Workbench};

use crate::audio::synth::Earcon;
use crate::audio::{AudioEngine, AudioSettings};
use crate::bench::{CopyLanded, Haptics};
use crate::device::HandGoal;
use crate::error::ClientError;
use crate::explore::{Exploration, Findings};
use crate::haptics::HapticsSettings;
use crate::input::{Action, PhantomInput, Situation};
use crate::speech::Speaker;
use crate::status::{self, MenuItem};

/// How the Phantom client runs.
#[derive(Resource, Clone, Debug, Default)]
pub struct PhantomSettings {
    /// Play by touch automatically (the touch bot).
    pub bot: bool,
    /// The haptic side.
    pub haptics: HapticsSettings,
    /// The audio side.
    pub audio: AudioSettings,
    /// The player's settings (file and command line) and where the menu saves them.
    pub prefs: crate::settings::plugin::Settings,
    /// The walkie-talkie's microphone and mode.
    pub voice: heist_voice::VoiceSettings,
}

/// What is on the workbench, for the spectator window: the copy, its mesh and its (public) colour.
#[derive(Resource, Default, Debug)]
pub struct BenchView {
    /// The copy, its mesh (workbench frame) and its look's sRGB colour.
    pub copy: Option<(ItemId, heist_shared::artifact::HapticMesh, [u8; 3])>,
}

/// When this client hosts: where the partner joins and with which code (said after the welcome), and
/// the code spelled in the NATO alphabet (said slowly, last, so R repeats it).
#[derive(Resource, Clone, Debug)]
pub struct HostedCode {
    /// "You host the heist. Your partner joins at … with the code …."
    pub intro: String,
    /// "The code, spelled: kilo, seven, …. R repeats it."
    pub spelled: String,
}

/// The speech rate the spelled code is said at most, words per minute.
pub const SPELLING_WPM: u32 = 120;

/// Adds the Phantom client to `app` (after the client core): opens the device, starts the haptic loop
/// and audio, and adds the plugin.
pub fn start(app: &mut App, settings: PhantomSettings) -> Result<(), ClientError> {
    let audio = AudioEngine::new(&settings.audio)?;
    start_with(app, settings, audio, Speaker::new())
}

/// [`start`] with the audio engine and speaker already running (the spoken prompts before joining
/// used them, and what they said stays in the same recording).
pub fn start_with(
    app: &mut App,
    settings: PhantomSettings,
    mut audio: AudioEngine,
    mut speaker: Speaker,
) -> Result<(), ClientError> {
    crate::bench::add_haptics(app, &settings.haptics)?;
    crate::settings::plugin::apply(&settings.prefs.run, &mut speaker, &mut audio);
    app.insert_non_send(audio).insert_non_send(speaker);
    app.insert_resource(settings.prefs.clone());
    app.add_plugins((PhantomClientPlugin { settings }, crate::settings::plugin::SettingsPlugin));
    Ok(())
}

/// The Phantom client's systems (see the module docs; use [`start`]).
pub struct PhantomClientPlugin {
    /// Settings.
    pub settings: PhantomSettings,
}

impl Plugin for PhantomClientPlugin {
    fn build(&self, app: &mut App) {
        crate::sound::init(app);
        app.insert_resource(self.settings.clone())
            .init_resource::<Menu>()
            .init_resource::<Workbench>()
            .init_resource::<HandSteering>()
            .init_resource::<PhantomInput>()
            .init_resource::<BenchView>()
            .add_message::<HeistEvent>()
            .add_message::<Action>()
            .configure_sets(Update, (PhantomSystems::Receive, PhantomSystems::Play, PhantomSystems::Sound).chain())
            .add_systems(Update, (receive, poll_haptics, watch_device).chain().in_set(PhantomSystems::Receive))
            .add_systems(
                Update,
                (
                    lobby,
                    (crate::input::read_keys, read_buttons, decide_actions),
                    (answer_menu, say_what_is_asked, leave, send_actions, steer_hand),
                    (start_new_round, after_verdict, touch_bot),
                )
                    .chain()
                    .in_set(PhantomSystems::Play),
            )
            .add_systems(
                Update,
                (announce_events, crate::sound::museum_sounds, crate::sound::contact_sound, speak, send_tool_pose)
                    .chain()
                    .in_set(PhantomSystems::Sound),
            );
    }
}

fn kind_of(items: &Query<&ItemView>, item: ItemId) -> Option<ArtifactKind> {
    items.iter().find(|i| i.id == item).and_then(|i| match i.kind {
        ItemKind::Copy { artifact, .. } => Some(artifact),
        ItemKind::Prop => None,
    })
}

/// Server events become [`HeistEvent`]s; a copy on the workbench goes to the haptic rig.
fn receive(
    mut inbox: ResMut<Inbox>,
    mut events: MessageWriter<HeistEvent>,
    mut state: ResMut<Workbench>,
    mut haptics: Haptics,
    mut bench: ResMut<BenchView>,
    items: Query<&ItemView>,
) {
    for e in std::mem::take(&mut inbox.events) {
        events.write(HeistEvent(e));
    }
    if let Some(copy) = inbox.workbench.take() {
        let kind = kind_of(&items, copy.item);
        haptics.bench.place(&copy);
        let colour = kind.map_or([200, 200, 200], |k| heist_shared::artifact::look(k).colour_srgb);
        bench.copy = Some((copy.item, copy.mesh.clone(), colour));
        state.copy = Some((copy.item, kind));
        state.feel = Some(MaterialClass::nearest(&copy.material));
        state.exploration = None;
        state.arrived = Some(kind);
    }
    // The item's replication may come a frame after the copy.
    if let Some((item, None)) = state.copy
        && let Some(kind) = kind_of(&items, item)
    {
        state.copy = Some((item, Some(kind)));
        if let Some(view) = bench.copy.as_mut() {
            view.2 = heist_shared::artifact::look(kind).colour_srgb;
        }
    }
}

/// Guides the player through the real device's set-up as the session goes (the Falcon's homing, a grip
/// read out of reach) and tells them, once, when it stopped answering (its link went: no force reaches it).
fn watch_device(
    haptics: Haptics,
    mut speaker: NonSendMut<Speaker>,
    mut guide: Local<crate::device::Guide>,
    mut started: Local<Option<std::time::Instant>>,
) {
    let started = *started.get_or_insert_with(std::time::Instant::now);
    if let Some(notice) = guide.next(haptics.device_reading(), started.elapsed().as_secs_f64()) {
        log::info!("device: {notice}");
        speaker.say(notice);
    }
}

/// Announces when the copy can be felt (or cannot).
fn poll_haptics(
    mut landed: MessageReader<CopyLanded>,
    mut speaker: NonSendMut<Speaker>,
    mut audio: NonSendMut<AudioEngine>,
    settings: Res<PhantomSettings>,
) {
    for CopyLanded { item, result } in landed.read() {
        match result {
            Ok(on) => {
                log::info!(
                    "copy {} on the bench: {} spheres{}{}",
                    on.item.0,
                    on.spheres,
                    if on.cached { " (cached)" } else { "" },
                    on.surface_bytes.map_or(String::new(), |b| format!(", its surface grid {:.1} MB", b as f64 / 1e6))
                );
                audio.earcon(Earcon::ReadyToFeel);
                if !settings.bot {
                    speaker.say("You can feel it now. Y if it is real, N if it is fake.");
                }
            }
            Err(reason) => {
                log::error!("{}", ClientError::Copy { item: item.0 as u32, reason: reason.clone() });
                speaker.say("This copy cannot be felt: its shape is broken.");
            }
        }
    }
}

fn session(q: &Query<&SessionView>) -> Option<SessionView> {
    q.iter().next().cloned()
}

/// Sends a verdict on `item`, says it, and records it on the bench.
fn send_verdict(
    bench: &mut Workbench,
    out: &mut MessageWriter<ClientMsg>,
    speaker: &mut Speaker,
    item: ItemId,
    real: bool,
    findings: Option<Findings>,
) {
    out.write(ClientMsg::Phantom(PhantomMsg::Verdict { item, real }));
    speaker.say(if real { "You say: real." } else { "You say: fake." });
    bench.give(item, real, findings);
}

/// Greets, reads the menu, and (bot) readies up.
fn lobby(
    mut state: ResMut<Menu>,
    inbox: Res<Inbox>,
    q: Query<&SessionView>,
    settings: Res<PhantomSettings>,
    hosted: Option<Res<HostedCode>>,
    mut speaker: NonSendMut<Speaker>,
    mut out: MessageWriter<ClientMsg>,
) {
    let Some(s) = session(&q) else { return };
    if inbox.role.is_none() {
        return;
    }
    if !state.greeted {
        state.greeted = true;
        speaker.say(
            "Welcome to Phantom Heist. You are Phantom, at the workbench. Up and down read the menu; Enter chooses.",
        );
        // A player who joins, or comes back, after the lobby hears where the heist stands instead.
        speaker.say(match s.phase {
            Phase::Lobby => MenuItem::ALL[0].label().to_owned(),
            Phase::Heist => format!("The heist is on. {}", status::status(&s, &[], None)),
            Phase::Won | Phase::Lost(_) => {
                format!("{} Enter asks for another round; Q leaves.", status::status(&s, &[], None))
            }
        });
        // Last, so R repeats the spelled code.
        if let Some(h) = hosted {
            speaker.say(h.intro.clone());
            speaker.say_slowly(h.spelled.clone(), SPELLING_WPM);
        }
    }
    if settings.bot && s.phase == Phase::Lobby && !state.ready_sent {
        out.write(ClientMsg::Lobby(LobbyMsg::Ready));
        state.ready_sent = true;
    }
    if s.phase == Phase::Heist && !state.briefed && !inbox.briefings.is_empty() {
        state.briefed = true;
        for b in &inbox.briefings {
            speaker.say(b.text.clone());
        }
    }
}

/// Reads the device's buttons into this frame's [`PhantomInput`]: the first pressed says real, else the
/// second fake (the touch bot's buttons are its own).
fn read_buttons(
    haptics: Haptics,
    settings: Res<PhantomSettings>,
    mut held: Local<u32>,
    mut input: ResMut<PhantomInput>,
) {
    let buttons = haptics.frame.device.buttons.0;
    let pressed = buttons & !*held;
    *held = buttons;
    if settings.bot {
        return;
    }
    if pressed & 1 != 0 {
        input.press(crate::input::Key::Real);
    } else if pressed & 2 != 0 {
        input.press(crate::input::Key::Fake);
    }
}

/// Decides what this frame's input asks for, where the game stands (`input::decide`).
fn decide_actions(
    input: Res<PhantomInput>,
    q: Query<&SessionView>,
    menu: Res<Menu>,
    workbench: Res<Workbench>,
    haptics: Haptics,
    mut actions: MessageWriter<Action>,
) {
    let Some(s) = session(&q) else { return };
    let situation = Situation {
        phase: s.phase,
        menu_item: menu.item,
        ready_sent: menu.ready_sent,
        held_copy: workbench.held(|item| haptics.bench.holds(item)),
        exploring: workbench.exploration.is_some(),
    };
    actions.write_batch(crate::input::decide(&input, &situation));
}

/// The menu's actions: an item read, ready sent, the settings menu opened.
fn answer_menu(
    mut actions: MessageReader<Action>,
    mut menu: ResMut<Menu>,
    mut speaker: NonSendMut<Speaker>,
    mut out: MessageWriter<ClientMsg>,
    mut open_settings: MessageWriter<crate::settings::plugin::OpenSettings>,
) {
    for action in actions.read() {
        match *action {
            Action::ReadMenu(item) => {
                menu.item = item;
                speaker.say(MenuItem::ALL[item % MenuItem::ALL.len()].label());
            }
            Action::Ready => {
                out.write(ClientMsg::Lobby(LobbyMsg::Ready));
                menu.ready_sent = true;
                speaker.say("Ready. Waiting for Vive.");
            }
            Action::OpenSettings => {
                open_settings.write(crate::settings::plugin::OpenSettings);
            }
            _ => {}
        }
    }
}

/// What Phantom asked to hear: a line, the status, the briefing, the keys, the last line again.
fn say_what_is_asked(
    mut actions: MessageReader<Action>,
    mut speaker: NonSendMut<Speaker>,
    q: Query<&SessionView>,
    guards: Query<&GuardView>,
    vive: Query<&ViveAvatar>,
    inbox: Res<Inbox>,
    prefs: Res<crate::settings::plugin::Settings>,
) {
    for action in actions.read() {
        match *action {
            Action::Say(line) => speaker.say(line),
            Action::SayStatus => {
                let Some(s) = session(&q) else { continue };
                let g: Vec<&GuardView> = guards.iter().collect();
                speaker.say(status::status(&s, &g, vive.iter().next().map(|v| v.position)));
            }
            Action::SayBriefing => {
                let b = inbox.briefings.iter().map(|b| b.text.as_str()).collect::<Vec<_>>().join(" ");
                speaker.say(if b.is_empty() { "No briefing yet.".to_owned() } else { b });
            }
            Action::SayHelp => speaker.say(status::help(prefs.run.talk_key.name())),
            Action::Repeat => speaker.repeat(),
            _ => {}
        }
    }
}

/// Leaves the session when asked (or ends the program when there is none to leave).
fn leave(
    mut actions: MessageReader<Action>,
    mut leaving: Option<ResMut<heist_client::Leaving>>,
    mut speaker: NonSendMut<Speaker>,
    time: Res<Time<Real>>,
    mut exit: MessageWriter<AppExit>,
) {
    for action in actions.read() {
        if *action != Action::Leave {
            continue;
        }
        match leaving.as_mut() {
            Some(leaving) => {
                speaker.say("Leaving the session.");
                leaving.start(time.elapsed_secs_f64());
            }
            None => {
                exit.write(AppExit::Success);
            }
        }
    }
}

/// What goes to the server: another round, warnings, verdicts.
fn send_actions(
    mut actions: MessageReader<Action>,
    mut workbench: ResMut<Workbench>,
    mut speaker: NonSendMut<Speaker>,
    mut out: MessageWriter<ClientMsg>,
) {
    for action in actions.read() {
        match *action {
            Action::Rematch => {
                out.write(ClientMsg::Lobby(LobbyMsg::Rematch));
            }
            Action::Warn(w) => {
                out.write(ClientMsg::Phantom(PhantomMsg::Warn(w)));
            }
            Action::Verdict { item, real } => send_verdict(&mut workbench, &mut out, &mut speaker, item, real, None),
            _ => {}
        }
    }
}

/// Moves the simulated hand where the held keys push it (`state::HandSteering`).
fn steer_hand(
    mut actions: MessageReader<Action>,
    mut hand: ResMut<HandSteering>,
    mut haptics: Haptics,
    time: Res<Time<Real>>,
) {
    for action in actions.read() {
        if let Action::MoveHand(direction) = *action {
            let target = hand.push(direction, time.delta_secs());
            haptics.steer(HandGoal::Hold(haptic_common::Pose::from_translation(target)));
        }
    }
}

/// A new round: the last round's copy, briefing, verdicts and hand mean nothing now.
fn start_new_round(
    mut events: MessageReader<HeistEvent>,
    mut menu: ResMut<Menu>,
    mut workbench: ResMut<Workbench>,
    mut hand: ResMut<HandSteering>,
    mut haptics: Haptics,
    mut bench: ResMut<BenchView>,
) {
    if events.read().any(|HeistEvent(e)| matches!(e, GameEvent::RoundStarted(_))) {
        menu.new_round();
        *workbench = Workbench::default();
        *hand = HandSteering::default();
        haptics.bench.clear();
        bench.copy = None;
    }
}

/// A right verdict takes the copy off the bench; a wrong one leaves it there, and the bot says the
/// other thing.
fn after_verdict(
    mut events: MessageReader<HeistEvent>,
    mut state: ResMut<Workbench>,
    settings: Res<PhantomSettings>,
    mut haptics: Haptics,
    mut bench: ResMut<BenchView>,
    mut speaker: NonSendMut<Speaker>,
    mut out: MessageWriter<ClientMsg>,
) {
    for HeistEvent(e) in events.read() {
        if let GameEvent::Verdict { item, declared_real, outcome } = e {
            if *outcome != VerdictOutcome::Wrong {
                if state.copy.is_some_and(|c| c.0 == *item) {
                    state.copy = None;
                    state.exploration = None;
                    haptics.bench.clear();
                    bench.copy = None;
                }
                continue;
            }
            if settings.bot && state.last_verdict == Some((*item, *declared_real)) {
                send_verdict(&mut state, &mut out, &mut speaker, *item, !declared_real, None);
            }
        }
    }
}

/// The touch bot: explores the copy with the simulated hand and gives its verdict from what it felt.
fn touch_bot(
    mut state: ResMut<Workbench>,
    mut haptics: Haptics,
    inbox: Res<Inbox>,
    settings: Res<PhantomSettings>,
    mut speaker: NonSendMut<Speaker>,
    mut out: MessageWriter<ClientMsg>,
) {
    if !settings.bot {
        return;
    }
    let now = haptics.now_us();
    // Start on a copy that can be felt, whose kind is known, and that was not judged yet.
    if state.exploration.is_none()
        && let Some((item, Some(kind))) = state.copy
        && haptics.bench.holds(item)
        && state.judged != Some(item)
    {
        let ex = Exploration::new(kind, now, haptics.stylus()).judging_springs(haptics.bench.hard_above_n_per_m());
        haptics.steer(ex.goal());
        state.exploration = Some(ex);
    }
    let Some(ex) = state.exploration.as_mut() else { return };
    let changed = ex.step(now, haptics.samples());
    if changed {
        haptics.steer(ex.goal());
    }
    if !ex.done() {
        return;
    }
    let Some(findings) = ex.findings().cloned() else { return };
    let Some((item, Some(kind))) = state.copy else { return };
    state.exploration = None;
    state.judged = Some(item);
    let briefing = inbox.briefings.iter().find(|b| b.kind == kind);
    let real = briefing.is_some_and(|b| findings.matches(b));
    log::info!(
        "touch bot: copy {} of the {}: felt {} -> {}",
        item.0,
        kind.name(),
        findings.describe(),
        if real { "real" } else { "fake" }
    );
    speaker.say(format!("I feel {}.", findings.spoken(kind)));
    send_verdict(&mut state, &mut out, &mut speaker, item, real, Some(findings));
}

/// Speaks what happened and plays the earcons.
fn announce_events(
    mut events: MessageReader<HeistEvent>,
    guards: Query<&GuardView>,
    mut spoken_alerts: Local<AlertMemory>,
    mut speaker: NonSendMut<Speaker>,
    mut audio: NonSendMut<AudioEngine>,
    mut state: ResMut<Workbench>,
    settings: Res<PhantomSettings>,
) {
    let bot = settings.bot;
    for HeistEvent(e) in events.read() {
        if !spoken_alerts.is_news(e) {
            continue;
        }
        let name = |id: u16| guards.iter().find(|g| g.id.0 == id).map(|g| g.name.clone());
        let text = status::announce(e, name).or_else(|| heist_client::notice::session_notice(e, Role::Phantom));
        if let Some(text) = text {
            speaker.say(text);
        }
        if matches!(e, GameEvent::PhaseChanged(Phase::Won | Phase::Lost(_))) && !bot {
            speaker.say("Enter asks for another round; Q leaves.");
        }
        if let Some(earcon) = earcon_for(e) {
            audio.earcon(earcon);
        }
    }
    if let Some(kind) = state.arrived.take() {
        audio.earcon(Earcon::CopyArrived);
        speaker.say(status::copy_arrived(kind));
    }
}

/// The earcon that goes with an event's words, if one does.
pub fn earcon_for(e: &GameEvent) -> Option<Earcon> {
    Some(match e {
        GameEvent::Joined(Role::Vive) | GameEvent::Resumed(Role::Vive) => Earcon::PartnerIn,
        GameEvent::Left { role: Role::Vive, .. } | GameEvent::GaveUp(Role::Vive) => Earcon::PartnerOut,
        GameEvent::WarningSeen(_) => Earcon::WarningHeard,
        GameEvent::Verdict { outcome: VerdictOutcome::Wrong, .. } => Earcon::Wrong,
        GameEvent::Verdict { .. } => Earcon::Right,
        GameEvent::Alarm(_) => Earcon::AlarmUp,
        GameEvent::PhaseChanged(Phase::Won) => Earcon::Won,
        GameEvent::PhaseChanged(Phase::Lost(_)) => Earcon::Lost,
        _ => return None,
    })
}

/// Each guard's alert is said once per change, and a new round starts every guard afresh.
#[derive(Default)]
struct AlertMemory(HashMap<u16, GuardAlert>);

impl AlertMemory {
    /// False for a guard's alert already said; true for everything else.
    fn is_news(&mut self, event: &GameEvent) -> bool {
        match event {
            GameEvent::RoundStarted(_) => {
                self.0.clear();
                true
            }
            GameEvent::GuardAlert { guard, alert, .. } => self.0.insert(guard.0, *alert) != Some(*alert),
            _ => true,
        }
    }
}

/// Plays speech as it becomes ready, one line after the other.
fn speak(mut speaker: NonSendMut<Speaker>, mut audio: NonSendMut<AudioEngine>) {
    for s in speaker.ready() {
        audio.speak(s);
    }
    audio.update();
}

/// Tells the server where the stylus is (20 times a second, during the heist) so Vive sees it move.
fn send_tool_pose(
    mut frames: Local<u64>,
    frame: Res<bevy_haptics::HapticFrame>,
    q: Query<&SessionView>,
    mut out: MessageWriter<ClientMsg>,
) {
    *frames += 1;
    if session(&q).is_none_or(|s| s.phase != Phase::Heist) || !frames.is_multiple_of(3) {
        return;
    }
    let pose = frame.tool;
    out.write(ClientMsg::Phantom(PhantomMsg::ToolPose { position: pose.translation, rotation: pose.rotation }));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_partners_coming_and_going_and_a_received_warning_each_have_an_earcon() {
        use heist_shared::protocol::WarningKind;
        assert_eq!(earcon_for(&GameEvent::Joined(Role::Vive)), Some(Earcon::PartnerIn));
        assert_eq!(earcon_for(&GameEvent::Resumed(Role::Vive)), Some(Earcon::PartnerIn));
        assert_eq!(earcon_for(&GameEvent::Left { role: Role::Vive, dropped: true }), Some(Earcon::PartnerOut));
        assert_eq!(earcon_for(&GameEvent::Left { role: Role::Vive, dropped: false }), Some(Earcon::PartnerOut));
        assert_eq!(earcon_for(&GameEvent::GaveUp(Role::Vive)), Some(Earcon::PartnerOut));
        assert_eq!(earcon_for(&GameEvent::WarningSeen(WarningKind::Hide)), Some(Earcon::WarningHeard));
        assert_eq!(earcon_for(&GameEvent::Joined(Role::Phantom)), None, "one's own joining is no news");
        let earcons = [Earcon::PartnerIn, Earcon::PartnerOut, Earcon::LinkDown, Earcon::LinkUp, Earcon::WarningHeard];
        let sounds: Vec<_> = earcons.iter().map(|e| crate::audio::synth::earcon(*e).frames.to_vec()).collect();
        for (i, a) in sounds.iter().enumerate() {
            assert!(a.iter().any(|f| f.left.abs() > 0.1), "{:?} is audible", earcons[i]);
            for b in &sounds[i + 1..] {
                assert_ne!(a, b, "each notice sounds different");
            }
        }
    }

    #[test]
    fn a_guards_alert_is_said_once_per_change_and_afresh_in_a_new_round() {
        use heist_shared::protocol::GuardId;
        let alert = |a| GameEvent::GuardAlert { guard: GuardId(1), alert: a, position: Vec2::ZERO };
        let mut memory = AlertMemory::default();
        assert!(memory.is_news(&alert(GuardAlert::Suspicious)));
        assert!(!memory.is_news(&alert(GuardAlert::Suspicious)), "said once");
        assert!(memory.is_news(&alert(GuardAlert::Chasing)));
        assert!(memory.is_news(&GameEvent::RoundStarted(2)));
        assert!(memory.is_news(&alert(GuardAlert::Chasing)), "a new round: the same alert is news again");
    }
}
