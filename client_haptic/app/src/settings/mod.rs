//! The player's settings: speech rate, the four volumes, HRTF on or off and the push-to-talk key, kept
//! in `settings.toml` in the platform's config directory (`~/.config/phantom-heist/` on Linux), read at
//! start-up and overridden by command-line flags.
//!
//! You need this module to add a setting or change where settings live. [`menu`] is the spoken menu that
//! edits them; [`SettingsPlugin`](crate::settings::plugin::SettingsPlugin) wires that menu into the app.
//! A file that cannot be read or understood never stops the client: the defaults are used and the
//! reason is both printed and spoken ([`Loaded::warning`]).

pub mod menu;
pub mod plugin;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// A key that can be the push-to-talk key (letters the game does not use, and Space and Tab).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
#[value(rename_all = "lowercase")]
pub enum TalkKey {
    /// V.
    V,
    /// T.
    T,
    /// Space.
    Space,
    /// Tab.
    Tab,
    /// F.
    F,
    /// K.
    K,
    /// P.
    P,
}

impl TalkKey {
    /// Every choice, in the menu's order.
    pub const ALL: [TalkKey; 7] =
        [TalkKey::V, TalkKey::T, TalkKey::Space, TalkKey::Tab, TalkKey::F, TalkKey::K, TalkKey::P];

    /// The key's name as spoken and as written in the file.
    pub fn name(self) -> &'static str {
        match self {
            TalkKey::V => "V",
            TalkKey::T => "T",
            TalkKey::Space => "Space",
            TalkKey::Tab => "Tab",
            TalkKey::F => "F",
            TalkKey::K => "K",
            TalkKey::P => "P",
        }
    }

    /// The keyboard key.
    pub fn key_code(self) -> bevy::input::keyboard::KeyCode {
        use bevy::input::keyboard::KeyCode;
        match self {
            TalkKey::V => KeyCode::KeyV,
            TalkKey::T => KeyCode::KeyT,
            TalkKey::Space => KeyCode::Space,
            TalkKey::Tab => KeyCode::Tab,
            TalkKey::F => KeyCode::KeyF,
            TalkKey::K => KeyCode::KeyK,
            TalkKey::P => KeyCode::KeyP,
        }
    }
}

/// Lowest and highest speech rate, words per minute (espeak-ng's `-s`).
pub const SPEECH_RATE_RANGE: (u32, u32) = (80, 400);

/// What the player set (the file's contents; a missing field takes its default).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlayerSettings {
    /// Speech rate, words per minute (80–400; default 175).
    pub speech_rate: u32,
    /// Speech volume, percent (0–100; default 100).
    pub speech_volume: u8,
    /// The museum's sounds and the contact sound, percent (0–100; default 100).
    pub sound_volume: u8,
    /// Earcons, percent (0–100; default 100).
    pub earcon_volume: u8,
    /// The partner's voice on the walkie-talkie, percent (0–100; default 100).
    pub voice_volume: u8,
    /// Place sounds with the HRTF (true) or with time and level differences only (default true).
    pub hrtf: bool,
    /// The push-to-talk key (default V).
    pub talk_key: TalkKey,
}

impl Default for PlayerSettings {
    fn default() -> Self {
        Self {
            speech_rate: 175,
            speech_volume: 100,
            sound_volume: 100,
            earcon_volume: 100,
            voice_volume: 100,
            hrtf: true,
            talk_key: TalkKey::V,
        }
    }
}

impl PlayerSettings {
    /// The first value out of its range, as "what: why"; `None` when every value is in range.
    pub fn out_of_range(&self) -> Option<String> {
        let (lo, hi) = SPEECH_RATE_RANGE;
        if !(lo..=hi).contains(&self.speech_rate) {
            return Some(format!("speech_rate {} is not within {lo} to {hi}", self.speech_rate));
        }
        for (name, v) in [
            ("speech_volume", self.speech_volume),
            ("sound_volume", self.sound_volume),
            ("earcon_volume", self.earcon_volume),
            ("voice_volume", self.voice_volume),
        ] {
            if v > 100 {
                return Some(format!("{name} {v} is above 100"));
            }
        }
        None
    }

    /// The settings as the file's text.
    pub fn to_toml(&self) -> String {
        let body = toml::to_string(self).unwrap_or_default();
        format!("# Phantom Heist: the Phantom client's settings (the settings menu writes this file).\n{body}")
    }

    /// Parses the file's text; the error says what is wrong and on which line.
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let settings: Self = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| text[..s.start.min(text.len())].lines().count().max(1));
            let what = e.message().trim_end_matches('.').to_owned();
            match line {
                Some(l) => format!("line {l}: {what}"),
                None => what,
            }
        })?;
        match settings.out_of_range() {
            Some(why) => Err(why),
            None => Ok(settings),
        }
    }
}

/// Where the settings file lives: `$XDG_CONFIG_HOME/phantom-heist/settings.toml` on Linux (the
/// platform's config directory elsewhere); `None` when the platform has no home directory.
pub fn default_path() -> Option<PathBuf> {
    directories::ProjectDirs::from("", "", "phantom-heist").map(|d| d.config_dir().join("settings.toml"))
}

/// The settings read at start-up.
#[derive(Clone, Debug, PartialEq)]
pub struct Loaded {
    /// What the file holds (the defaults when there is no file or it is bad).
    pub settings: PlayerSettings,
    /// Why the file was not used, for the player (printed and spoken); `None` when it was, or when there
    /// was none yet.
    pub warning: Option<String>,
}

/// Reads the settings file at `path`; a missing file is the defaults, a bad one the defaults with a
/// warning that names the file and what is wrong.
pub fn load(path: &Path) -> Loaded {
    let bad = |why: String| Loaded {
        settings: PlayerSettings::default(),
        warning: Some(format!("The settings file {} is not usable ({why}); using the defaults.", path.display())),
    };
    match std::fs::read(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Loaded { settings: PlayerSettings::default(), warning: None }
        }
        Err(e) => bad(e.to_string()),
        Ok(bytes) => match String::from_utf8(bytes) {
            Err(_) => bad("it is not text".to_owned()),
            Ok(text) => match PlayerSettings::from_toml(&text) {
                Ok(settings) => Loaded { settings, warning: None },
                Err(why) => bad(why),
            },
        },
    }
}

/// Writes `settings` to `path` (creating its directory), replacing the file at once so a crash never
/// leaves half a file.
pub fn save(path: &Path, settings: &PlayerSettings) -> std::io::Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension("toml.new");
    std::fs::write(&tmp, settings.to_toml())?;
    std::fs::rename(&tmp, path)
}

/// Settings given on the command line for this run only (each overrides the file's value).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overrides {
    /// `--speech-rate`.
    pub speech_rate: Option<u32>,
    /// `--speech-volume`.
    pub speech_volume: Option<u8>,
    /// `--sound-volume`.
    pub sound_volume: Option<u8>,
    /// `--earcon-volume`.
    pub earcon_volume: Option<u8>,
    /// `--voice-volume`.
    pub voice_volume: Option<u8>,
    /// `--no-hrtf` (Some(false)).
    pub hrtf: Option<bool>,
    /// `--talk-key`.
    pub talk_key: Option<TalkKey>,
}

impl Overrides {
    /// `file` with these overrides applied.
    pub fn apply(&self, file: PlayerSettings) -> PlayerSettings {
        PlayerSettings {
            speech_rate: self.speech_rate.unwrap_or(file.speech_rate),
            speech_volume: self.speech_volume.unwrap_or(file.speech_volume),
            sound_volume: self.sound_volume.unwrap_or(file.sound_volume),
            earcon_volume: self.earcon_volume.unwrap_or(file.earcon_volume),
            voice_volume: self.voice_volume.unwrap_or(file.voice_volume),
            hrtf: self.hrtf.unwrap_or(file.hrtf),
            talk_key: self.talk_key.unwrap_or(file.talk_key),
        }
    }
}

/// A volume in percent as kira decibels (0 % is silence).
pub fn decibels(percent: u8) -> f32 {
    if percent == 0 { kira::Decibels::SILENCE.0 } else { 20.0 * (f32::from(percent.min(100)) / 100.0).log10() }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        std::env::temp_dir().join(format!("phantom-settings-{}-{name}", std::process::id())).join("settings.toml")
    }

    #[test]
    fn settings_round_trip_through_the_file() {
        let path = temp("round-trip");
        let settings = PlayerSettings {
            speech_rate: 250,
            speech_volume: 70,
            sound_volume: 40,
            earcon_volume: 0,
            voice_volume: 90,
            hrtf: false,
            talk_key: TalkKey::Space,
        };
        save(&path, &settings).expect("saves");
        assert_eq!(load(&path), Loaded { settings, warning: None });
        let text = std::fs::read_to_string(&path).expect("reads");
        assert!(text.contains("talk_key = \"space\"") && text.contains("hrtf = false"), "{text}");
    }

    #[test]
    fn no_file_is_the_defaults_without_a_warning() {
        assert_eq!(load(&temp("missing")), Loaded { settings: PlayerSettings::default(), warning: None });
    }

    #[test]
    fn a_corrupt_file_falls_back_to_the_defaults_with_a_warning_that_says_where() {
        let path = temp("corrupt");
        std::fs::create_dir_all(path.parent().expect("dir")).expect("dir");
        std::fs::write(&path, "speech_rate = 200\nsound_volume = \"loud\"\n").expect("writes");
        let loaded = load(&path);
        assert_eq!(loaded.settings, PlayerSettings::default());
        let warning = loaded.warning.expect("a warning");
        assert!(warning.contains("line 2") && warning.contains(&path.display().to_string()), "{warning}");
        std::fs::write(&path, "speech_rate = 9000\n").expect("writes");
        let warning = load(&path).warning.expect("a warning");
        assert!(warning.contains("speech_rate 9000 is not within 80 to 400"), "{warning}");
        std::fs::write(&path, "volume = 3\n").expect("writes");
        assert!(load(&path).warning.expect("a warning").contains("unknown field"), "a misspelt name is reported");
        std::fs::write(&path, [0xff, 0xfe, 0x00]).expect("writes");
        assert!(load(&path).warning.expect("a warning").contains("not text"));
    }

    #[test]
    fn a_partial_file_keeps_the_defaults_for_what_it_does_not_name() {
        let s = PlayerSettings::from_toml("speech_rate = 220\n").expect("parses");
        assert_eq!(s, PlayerSettings { speech_rate: 220, ..Default::default() });
    }

    #[test]
    fn command_line_flags_override_the_file_for_this_run() {
        let file = PlayerSettings { speech_rate: 250, hrtf: true, ..Default::default() };
        let flags = Overrides { hrtf: Some(false), talk_key: Some(TalkKey::T), ..Default::default() };
        let run = flags.apply(file);
        assert_eq!((run.speech_rate, run.hrtf, run.talk_key), (250, false, TalkKey::T));
    }

    #[test]
    fn volumes_map_to_decibels_with_zero_silent() {
        assert_eq!(decibels(100), 0.0);
        assert!((decibels(50) + 6.02).abs() < 0.01);
        assert_eq!(decibels(0), kira::Decibels::SILENCE.0);
    }
}
