//! The settings menu in the app: O (or the lobby menu's Settings item) opens it in the lobby and in the
//! heist; while it is open the arrows and Enter belong to it; each change is heard at once (the speech
//! rate and volumes change, a sample of the changed group plays) and closing saves the file.

use std::path::PathBuf;

use bevy::input::ButtonInput;
use bevy::input::keyboard::KeyCode;
use bevy::prelude::*;

use super::menu::{MenuKey, MenuOutcome, Setting, SettingsMenu};
use super::{Overrides, PlayerSettings, decibels, load, save};
use crate::audio::synth::Earcon;
use crate::audio::{AudioEngine, Volumes};
use crate::speech::Speaker;

/// The settings in force, the file's, and the menu when it is open.
#[derive(Resource, Clone, Debug, Default)]
pub struct Settings {
    /// Where the menu saves (`None`: changes last for this run only).
    pub path: Option<PathBuf>,
    /// What the file holds (what the menu saves).
    pub file: PlayerSettings,
    /// What is in force: the file with the command line's overrides.
    pub run: PlayerSettings,
    /// Why the file was not used, said at start-up.
    pub warning: Option<String>,
    menu: Option<SettingsMenu>,
}

impl Settings {
    /// Reads the file at `path` (see [`super::load`]) and applies `overrides`.
    pub fn load(path: Option<PathBuf>, overrides: &Overrides) -> Self {
        let loaded = path.as_deref().map(load).unwrap_or(super::Loaded { settings: Default::default(), warning: None });
        Self { path, file: loaded.settings, run: overrides.apply(loaded.settings), warning: loaded.warning, menu: None }
    }

    /// `run` in force, with no file (changes last for this run only).
    pub fn for_run(run: PlayerSettings) -> Self {
        Self { path: None, file: run, run, warning: None, menu: None }
    }

    /// True while the menu is open (it has the arrows and Enter).
    pub fn is_open(&self) -> bool {
        self.menu.is_some()
    }
}

/// Asks for the settings menu to open (the lobby menu's item sends it).
#[derive(Message, Clone, Copy, Debug)]
pub struct OpenSettings;

/// Puts the settings in force: speech rate, volumes and HRTF.
pub fn apply(run: &PlayerSettings, speaker: &mut Speaker, audio: &mut AudioEngine) {
    speaker.set_rate(run.speech_rate);
    audio.set_volumes(Volumes {
        speech_db: decibels(run.speech_volume),
        sound_db: decibels(run.sound_volume),
        earcon_db: decibels(run.earcon_volume),
        voice_db: decibels(run.voice_volume),
    });
    audio.set_hrtf(run.hrtf);
}

/// The settings menu and the settings at start-up.
pub struct SettingsPlugin;

impl Plugin for SettingsPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Settings>()
            .add_message::<OpenSettings>()
            .add_systems(Startup, warn_of_a_bad_file)
            .add_systems(Update, settings_keys.before(crate::schedule::PhantomSystems::Play));
    }
}

/// Says (and so prints) why the settings file was not used.
fn warn_of_a_bad_file(settings: Res<Settings>, mut speaker: NonSendMut<Speaker>) {
    if let Some(w) = &settings.warning {
        log::warn!("{w}");
        speaker.say(w.clone());
    }
}

const MENU_KEYS: [(KeyCode, MenuKey); 7] = [
    (KeyCode::ArrowUp, MenuKey::Up),
    (KeyCode::ArrowDown, MenuKey::Down),
    (KeyCode::ArrowLeft, MenuKey::Left),
    (KeyCode::ArrowRight, MenuKey::Right),
    (KeyCode::Enter, MenuKey::Close),
    (KeyCode::Escape, MenuKey::Close),
    (KeyCode::KeyO, MenuKey::Close),
];

/// Opens the menu (O, or [`OpenSettings`]); while open, takes its keys from the game and acts on them.
fn settings_keys(
    keys: Option<ResMut<ButtonInput<KeyCode>>>,
    mut open: MessageReader<OpenSettings>,
    mut settings: ResMut<Settings>,
    mut speaker: NonSendMut<Speaker>,
    mut audio: NonSendMut<AudioEngine>,
) {
    let asked = open.read().count() > 0;
    let Some(mut keys) = keys else { return };
    let Settings { path, file, run, menu, .. } = &mut *settings;
    let Some(m) = menu.as_mut() else {
        if asked || keys.just_pressed(KeyCode::KeyO) {
            keys.clear_just_pressed(KeyCode::KeyO);
            let m = SettingsMenu::default();
            for line in m.opening(run) {
                speaker.say(line);
            }
            *menu = Some(m);
        }
        return;
    };
    let pressed: Vec<MenuKey> = MENU_KEYS.iter().filter(|(k, _)| keys.just_pressed(*k)).map(|(_, m)| *m).collect();
    for (k, _) in MENU_KEYS {
        keys.clear_just_pressed(k);
    }
    for key in pressed {
        match m.press(key, run) {
            MenuOutcome::Say(line) => speaker.say(line),
            MenuOutcome::Changed(setting, line) => {
                setting.copy(run, file);
                apply(run, &mut speaker, &mut audio);
                sample(setting, &mut audio);
                speaker.say(line);
            }
            MenuOutcome::Closed => {
                let said = match path.as_deref() {
                    Some(p) => match save(p, file) {
                        Ok(()) => "Settings saved. Back to the game.".to_owned(),
                        Err(e) => {
                            format!("Settings kept for this session only: {} could not be written ({e}).", p.display())
                        }
                    },
                    None => "Settings kept for this session. Back to the game.".to_owned(),
                };
                speaker.say(said);
                *menu = None;
                return;
            }
        }
    }
}

/// A sound of the group a setting changed, so its new level is heard.
fn sample(setting: Setting, audio: &mut AudioEngine) {
    match setting {
        Setting::SoundVolume => audio.footstep(glam::Vec3::new(0.0, -1.6, -1.5), 0.6, "settings sample"),
        Setting::EarconVolume => audio.earcon(Earcon::CopyArrived),
        Setting::VoiceVolume => {
            let _ = audio.play_partner(crate::audio::synth::earcon(Earcon::SquelchOpen));
        }
        Setting::SpeechRate | Setting::SpeechVolume | Setting::Hrtf | Setting::TalkKey => {}
    }
}
