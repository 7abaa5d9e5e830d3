//! The Phantom client as a Bevy app: the session (through the shared client core), the copy on the
//! workbench, verdicts, speech, sounds, keys, and the touch bot.
//!
//! You need this module to run Phantom. [`start`] opens the device, the haptic loop and the audio engine
//! (they can fail, so they are set up before the plugin) and adds [`PhantomClientPlugin`]. Systems run in
//! [`PhantomSystems`] order each frame: `Receive` (server events and copies in), `Play` (lobby, keys,
//! verdicts, the bot), `Sound` (speech, museum sounds, contact sound); all in `Update`.

use std::collections::HashMap;

use bevy::input::ButtonInput;
use bevy::input::keyboard::KeyCode;
use bevy::prelude::*;
use glam::{Vec2, Vec3};
use heist_client::Inbox;
use heist_shared::artifact::{ArtifactKind, MaterialClass};
use heist_shared::protocol::{
    ClientMsg, GameEvent, GuardAlert, GuardView, ItemId, ItemKind, ItemView, LobbyMsg, NoiseKind, PhantomMsg, Phase,
    Role, SessionView, VerdictOutcome, ViveAvatar, WarningKind,
};

use crate::audio::synth::{ContactParams, Earcon};
use crate::audio::{AudioEngine, AudioSettings, listener_offset};
use crate::bench::{CopyLanded, Haptics};
use crate::device::HandGoal;
use crate::error::ClientError;
use crate::explore::{Exploration, Findings};
use crate::haptics::HapticsSettings;
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

/// A server event, re-sent as a Bevy message so every system can read it.
#[derive(Message, Clone, Debug, PartialEq)]
pub struct HeistEvent(pub GameEvent);

/// System sets of the Phantom client, chained in `Update`.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum PhantomSystems {
    /// Server events and copies in; the haptic rig polled.
    Receive,
    /// Lobby, keys, verdicts, the bot.
    Play,
    /// Speech, museum sounds, contact sound, tool pose out.
    Sound,
}

/// What one verdict was based on.
#[derive(Clone, Debug, PartialEq)]
pub struct VerdictRecord {
    /// The copy.
    pub item: ItemId,
    /// Declared real.
    pub real: bool,
    /// What touch found (bot only).
    pub findings: Option<Findings>,
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

/// The Phantom client's memory.
#[derive(Resource, Default, Debug)]
pub struct PhantomState {
    ready_sent: bool,
    greeted: bool,
    briefed: bool,
    menu: usize,
    /// The copy on the bench and its kind (from the replicated item, never its data).
    pub copy: Option<(ItemId, Option<ArtifactKind>)>,
    /// The copy's material class, for the contact sound only.
    copy_feel: Option<MaterialClass>,
    /// A copy arrived this frame (of this kind, if known): said after this frame's events, so the
    /// answer to the last verdict comes before the next copy.
    arrived: Option<Option<ArtifactKind>>,
    exploration: Option<Exploration>,
    last_verdict: Option<(ItemId, bool)>,
    judged: Option<ItemId>,
    /// Every verdict given.
    pub verdicts: Vec<VerdictRecord>,
    buttons: u32,
    touching: bool,
    last_tool: Option<(u64, Vec3)>,
    frame: u64,
    steps: HashMap<u16, Vec2>,
    vive_step: Option<Vec2>,
    /// The hand target moved by the keys (sim device), scene frame.
    hand_target: Option<Vec3>,
}

impl PhantomState {
    /// Forgets the last round (a rematch began); the greeting and the menu stay.
    fn new_round(&mut self) {
        *self = Self { greeted: self.greeted, ready_sent: true, menu: self.menu, ..Self::default() };
    }

    /// True while the haptic side is busy with a copy in real time (a tree building or the bot
    /// exploring): a test stepping the clock by hand should keep to wall-clock time meanwhile.
    pub fn busy(&self) -> bool {
        self.exploration.is_some() || self.copy.is_some_and(|c| self.judged != Some(c.0))
    }
}

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
        app.insert_resource(self.settings.clone())
            .init_resource::<PhantomState>()
            .init_resource::<BenchView>()
            .add_message::<HeistEvent>()
            .configure_sets(Update, (PhantomSystems::Receive, PhantomSystems::Play, PhantomSystems::Sound).chain())
            .add_systems(Update, (receive, poll_haptics, watch_device).chain().in_set(PhantomSystems::Receive))
            .add_systems(
                Update,
                (lobby, keys, device_buttons, after_verdict, touch_bot).chain().in_set(PhantomSystems::Play),
            )
            .add_systems(
                Update,
                (announce_events, museum_sounds, contact_sound, speak, send_tool_pose)
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
#[allow(clippy::too_many_arguments)]
fn receive(
    mut inbox: ResMut<Inbox>,
    mut events: MessageWriter<HeistEvent>,
    mut state: ResMut<PhantomState>,
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
        state.copy_feel = Some(MaterialClass::nearest(&copy.material));
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

fn send_verdict(
    state: &mut PhantomState,
    out: &mut MessageWriter<ClientMsg>,
    speaker: &mut Speaker,
    item: ItemId,
    real: bool,
    findings: Option<Findings>,
) {
    out.write(ClientMsg::Phantom(PhantomMsg::Verdict { item, real }));
    speaker.say(if real { "You say: real." } else { "You say: fake." });
    state.last_verdict = Some((item, real));
    state.verdicts.push(VerdictRecord { item, real, findings });
}

/// Greets, reads the menu, and (bot) readies up.
fn lobby(
    mut state: ResMut<PhantomState>,
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

/// Keyboard: menu, verdicts, status, briefing, repeat, warnings, and the simulated hand.
#[allow(clippy::too_many_arguments)]
fn keys(
    keys: Option<Res<ButtonInput<KeyCode>>>,
    time: Res<Time<Real>>,
    mut state: ResMut<PhantomState>,
    inbox: Res<Inbox>,
    q: Query<&SessionView>,
    guards: Query<&GuardView>,
    vive: Query<&ViveAvatar>,
    mut speaker: NonSendMut<Speaker>,
    mut haptics: Haptics,
    mut out: MessageWriter<ClientMsg>,
    mut leaving: Option<ResMut<heist_client::Leaving>>,
    mut exit: MessageWriter<AppExit>,
    (prefs, mut open_settings): (
        Res<crate::settings::plugin::Settings>,
        MessageWriter<crate::settings::plugin::OpenSettings>,
    ),
) {
    let Some(keys) = keys else { return };
    let Some(s) = session(&q) else { return };
    if prefs.is_open() {
        return; // the settings menu has the keys
    }
    let status_line = |_: &PhantomState| {
        let g: Vec<&GuardView> = guards.iter().collect();
        status::status(&s, &g, vive.iter().next().map(|v| v.position))
    };
    let briefing = || inbox.briefings.iter().map(|b| b.text.as_str()).collect::<Vec<_>>().join(" ");
    if s.phase == Phase::Lobby {
        let n = MenuItem::ALL.len();
        if keys.just_pressed(KeyCode::ArrowDown) {
            state.menu = (state.menu + 1) % n;
            speaker.say(MenuItem::ALL[state.menu].label());
        }
        if keys.just_pressed(KeyCode::ArrowUp) {
            state.menu = (state.menu + n - 1) % n;
            speaker.say(MenuItem::ALL[state.menu].label());
        }
        if keys.just_pressed(KeyCode::Enter) {
            match MenuItem::ALL[state.menu] {
                MenuItem::Ready if !state.ready_sent => {
                    out.write(ClientMsg::Lobby(LobbyMsg::Ready));
                    state.ready_sent = true;
                    speaker.say("Ready. Waiting for Vive.");
                }
                MenuItem::Ready => speaker.say("You are ready. Waiting for Vive."),
                MenuItem::Briefing => speaker.say("The briefing comes when the heist begins."),
                MenuItem::Status => speaker.say(status_line(&state)),
                MenuItem::Settings => {
                    open_settings.write(crate::settings::plugin::OpenSettings);
                }
                MenuItem::Help => speaker.say(status::help(prefs.run.talk_key.name())),
            }
        }
    }
    if matches!(s.phase, Phase::Won | Phase::Lost(_)) && keys.just_pressed(KeyCode::Enter) {
        out.write(ClientMsg::Lobby(LobbyMsg::Rematch));
    }
    if keys.just_pressed(KeyCode::KeyQ) {
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
    if keys.just_pressed(KeyCode::KeyR) {
        speaker.repeat();
    }
    if keys.just_pressed(KeyCode::KeyS) {
        speaker.say(status_line(&state));
    }
    if keys.just_pressed(KeyCode::KeyB) {
        let b = briefing();
        speaker.say(if b.is_empty() { "No briefing yet.".to_owned() } else { b });
    }
    if s.phase == Phase::Heist {
        for (key, w) in [
            (KeyCode::KeyH, WarningKind::Hide),
            (KeyCode::KeyG, WarningKind::Go),
            (KeyCode::KeyC, WarningKind::ComeBack),
        ] {
            if keys.just_pressed(key) {
                out.write(ClientMsg::Phantom(PhantomMsg::Warn(w)));
            }
        }
        if let Some((item, _)) = state.copy
            && haptics.bench.holds(item)
        {
            for (key, real) in [(KeyCode::KeyY, true), (KeyCode::KeyN, false)] {
                if keys.just_pressed(key) {
                    send_verdict(&mut state, &mut out, &mut speaker, item, real, None);
                }
            }
        }
    }
    // Arrow keys move the simulated hand in the horizontal plane, page up/down vertically (10 cm/s).
    let mut d = Vec3::ZERO;
    for (key, dir) in [
        (KeyCode::ArrowLeft, Vec3::NEG_X),
        (KeyCode::ArrowRight, Vec3::X),
        (KeyCode::ArrowUp, Vec3::NEG_Z),
        (KeyCode::ArrowDown, Vec3::Z),
        (KeyCode::PageUp, Vec3::Y),
        (KeyCode::PageDown, Vec3::NEG_Y),
    ] {
        if keys.pressed(key) && s.phase != Phase::Lobby {
            d += dir;
        }
    }
    if d != Vec3::ZERO && state.exploration.is_none() {
        let at = *state.hand_target.get_or_insert(Vec3::new(0.0, 0.06, 0.07));
        let next = (at + d * 0.1 * time.delta_secs()).clamp(Vec3::splat(-0.12), Vec3::splat(0.12));
        state.hand_target = Some(next);
        haptics.steer(HandGoal::Hold(haptic_common::Pose::from_translation(next)));
    }
}

/// Device buttons: the first says real, the second fake (on press).
fn device_buttons(
    mut state: ResMut<PhantomState>,
    haptics: Haptics,
    settings: Res<PhantomSettings>,
    mut speaker: NonSendMut<Speaker>,
    mut out: MessageWriter<ClientMsg>,
) {
    let buttons = haptics.frame.device.buttons.0;
    let pressed = buttons & !state.buttons;
    state.buttons = buttons;
    if settings.bot || pressed == 0 {
        return;
    }
    if let Some((item, _)) = state.copy
        && haptics.bench.holds(item)
    {
        if pressed & 1 != 0 {
            send_verdict(&mut state, &mut out, &mut speaker, item, true, None);
        } else if pressed & 2 != 0 {
            send_verdict(&mut state, &mut out, &mut speaker, item, false, None);
        }
    }
}

/// A right verdict takes the copy off the bench; a wrong one leaves it there, and the bot says the
/// other thing.
fn after_verdict(
    mut events: MessageReader<HeistEvent>,
    mut state: ResMut<PhantomState>,
    settings: Res<PhantomSettings>,
    mut haptics: Haptics,
    mut bench: ResMut<BenchView>,
    mut speaker: NonSendMut<Speaker>,
    mut out: MessageWriter<ClientMsg>,
) {
    for HeistEvent(e) in events.read() {
        if let GameEvent::RoundStarted(_) = e {
            // A new round: the last round's copy, briefing and verdicts mean nothing now.
            state.new_round();
            haptics.bench.clear();
            bench.copy = None;
            continue;
        }
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
    mut state: ResMut<PhantomState>,
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
    mut state: ResMut<PhantomState>,
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

/// The museum around Phantom's workbench: noises, guards' steps and barks, Vive's steps, the alarm.
fn museum_sounds(
    mut events: MessageReader<HeistEvent>,
    mut state: ResMut<PhantomState>,
    inbox: Res<Inbox>,
    guards: Query<&GuardView>,
    vive: Query<&ViveAvatar>,
    mut audio: NonSendMut<AudioEngine>,
) {
    let Some(bench) = inbox.level.as_ref().map(|l| l.workbench) else { return };
    let at = |p: Vec2, h: f32| listener_offset(bench, p, h);
    for HeistEvent(e) in events.read() {
        match e {
            GameEvent::Noise { kind: NoiseKind::Glass, position, .. } => audio.glass(at(*position, 1.0)),
            GameEvent::Noise { kind: NoiseKind::Thud, position, .. } => audio.thud(at(*position, 0.0)),
            GameEvent::Noise { kind: NoiseKind::Alarm, position, .. } => audio.alarm(at(*position, 2.5)),
            GameEvent::Noise { kind: NoiseKind::Footsteps, position, loudness } => {
                audio.footstep(at(*position, 0.0), *loudness, "vive footstep")
            }
            GameEvent::Radio { from, .. } => {
                audio.play_at(crate::audio::synth::radio_squawk(), at(*from, 1.4), "guard radio")
            }
            GameEvent::GuardAlert { alert, position, .. } => {
                if matches!(alert, GuardAlert::Suspicious | GuardAlert::Chasing) {
                    audio.play_at(
                        crate::audio::synth::bark(*alert == GuardAlert::Chasing),
                        at(*position, 1.7),
                        "guard bark",
                    );
                }
            }
            _ => {}
        }
    }
    // A step every 0.7 m a guard walks; Vive's steps are quiet unless she runs.
    for g in &guards {
        let last = state.steps.entry(g.id.0).or_insert(g.position);
        if g.position.distance(*last) > 0.7 {
            *last = g.position;
            audio.footstep(at(g.position, 0.0), 0.5, "guard footstep");
        }
    }
    if let Some(v) = vive.iter().next() {
        let last = *state.vive_step.get_or_insert(v.position);
        if v.position.distance(last) > 0.7 {
            state.vive_step = Some(v.position);
            let loud = match v.stance {
                heist_shared::protocol::Stance::Crouching => 0.1,
                heist_shared::protocol::Stance::Running => 0.6,
                heist_shared::protocol::Stance::Standing => 0.25,
            };
            audio.footstep(at(v.position, 0.0), loud, "vive footstep");
        }
    }
}

/// Drives the contact sound from this frame's haptic samples: force and sliding speed, taps on impact.
fn contact_sound(mut state: ResMut<PhantomState>, haptics: Haptics, mut audio: NonSendMut<AudioEngine>) {
    let feel = state.copy_feel;
    let params = contact_params(haptics.samples(), &mut state.last_tool, feel);
    let touching = params.force_n > 0.05;
    if touching && !state.touching {
        audio.tap((params.force_n / 2.0).min(1.0));
    }
    state.touching = touching;
    audio.contact(params);
}

/// The contact sound's parameters from force samples (mean contact force and sliding speed of the
/// stylus); `last` carries the previous sample between frames; `feel` sets hardness and roughness,
/// and a ribbed copy's ridges tick at the rate the stylus crosses them (its speed up or down the copy
/// over their spacing).
pub fn contact_params(
    samples: &[haptic_rig::ForceSample],
    last: &mut Option<(u64, Vec3)>,
    feel: Option<MaterialClass>,
) -> ContactParams {
    let (mut force, mut speed, mut climb, mut n) = (0.0, 0.0, 0.0, 0u32);
    for s in samples {
        let f = s.contact_force.length();
        if let Some((t, p)) = *last
            && s.t_us > t
        {
            let v = (s.tool_position - p) / ((s.t_us - t) as f32 * 1e-6);
            let normal = s.contact_force.normalize_or_zero();
            let slip = v - normal * v.dot(normal);
            speed += slip.length();
            climb += slip.y.abs();
        }
        *last = Some((s.t_us, s.tool_position));
        force += f;
        n += 1;
    }
    if n == 0 {
        return ContactParams::default();
    }
    let feel = feel.unwrap_or(MaterialClass::HardSmooth);
    let ridges_per_s = feel.material().ridges.map_or(0.0, |r| climb / n as f32 / r.spacing_m);
    ContactParams {
        force_n: force / n as f32,
        slip_m_per_s: speed / n as f32,
        hardness: if feel.is_hard() { 1.0 } else { 0.2 },
        roughness: if feel.is_rough() { 1.0 } else { 0.1 },
        ridges_per_s,
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
    mut state: ResMut<PhantomState>,
    frame: Res<bevy_haptics::HapticFrame>,
    q: Query<&SessionView>,
    mut out: MessageWriter<ClientMsg>,
) {
    state.frame += 1;
    if session(&q).is_none_or(|s| s.phase != Phase::Heist) || !state.frame.is_multiple_of(3) {
        return;
    }
    let pose = frame.tool;
    out.write(ClientMsg::Phantom(PhantomMsg::ToolPose { position: pose.translation, rotation: pose.rotation }));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::audio::{AudioOutput, SpatialMode};
    use haptic_rig::ForceSample;

    /// A second of 1 kHz samples of the stylus sliding along +x at `speed` m/s, pushed with `force` N.
    fn stroke(force: f32, speed: f32) -> Vec<ForceSample> {
        (0..1000u64)
            .map(|i| ForceSample {
                t_us: 1_000_000 + i * 1000,
                contact_force: Vec3::Y * force,
                tool_position: Vec3::X * speed * i as f32 * 1e-3,
                contacts: if force > 0.0 { 12 } else { 0 },
                ..Default::default()
            })
            .collect()
    }

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

    #[test]
    fn haptic_contact_drives_the_contact_sound_and_free_space_leaves_it_silent() {
        let mut audio = AudioEngine::new(&AudioSettings {
            output: AudioOutput::Manual,
            spatial: SpatialMode::Hrtf,
            ..Default::default()
        })
        .expect("audio starts");
        let capture = audio.capture().expect("memory output").clone();
        let energy = |frames: Vec<(f32, f32)>| frames.iter().map(|f| f.0 * f.0 + f.1 * f.1).sum::<f32>();
        let mut last = None;
        let free = contact_params(&stroke(0.0, 0.05), &mut last, Some(MaterialClass::HardRough));
        assert_eq!(free.force_n, 0.0);
        audio.contact(free);
        assert!(energy(capture.render(24_000)) < 1e-9, "free space is silent");
        let mut last = None;
        let sliding = contact_params(&stroke(1.2, 0.05), &mut last, Some(MaterialClass::HardRough));
        assert!((sliding.force_n - 1.2).abs() < 1e-4 && (sliding.slip_m_per_s - 0.05).abs() < 1e-3, "{sliding:?}");
        audio.contact(sliding);
        assert!(energy(capture.render(24_000)) > 1e-2, "the stylus sliding on a copy is heard");
    }

    #[test]
    fn stroking_up_a_ribbed_copy_ticks_once_per_ridge_crossed_and_a_smooth_one_never() {
        // Up the side of the copy (pressed along −x) at 6 cm/s: 20 ridges 3 mm apart a second.
        let up: Vec<ForceSample> = stroke(1.0, 0.06)
            .into_iter()
            .map(|s| ForceSample {
                contact_force: Vec3::X,
                tool_position: Vec3::new(0.04, s.tool_position.x, 0.0),
                ..s
            })
            .collect();
        let ribbed = contact_params(&up, &mut None, Some(MaterialClass::SoftRough));
        assert!((ribbed.ridges_per_s - 20.0).abs() < 0.1, "{ribbed:?}");
        assert_eq!(contact_params(&up, &mut None, Some(MaterialClass::SoftSmooth)).ridges_per_s, 0.0);
        // Round the copy, along the ridges: none crossed.
        assert!(contact_params(&stroke(1.0, 0.06), &mut None, Some(MaterialClass::SoftRough)).ridges_per_s < 1e-3);
    }
}
