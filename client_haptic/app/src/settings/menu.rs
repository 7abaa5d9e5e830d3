//! The settings menu as a blind player hears it: up and down go from setting to setting, left and right
//! change the one heard last, Enter (or Escape, or the key that opened it) closes it and saves.
//!
//! You need this module to change what a setting says or how it steps. Pure: settings and key presses
//! in, the sentence to say out.

use super::{PlayerSettings, SPEECH_RATE_RANGE, TalkKey};

/// One line of the menu.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Setting {
    /// Words per minute.
    SpeechRate,
    /// Percent.
    SpeechVolume,
    /// Percent.
    SoundVolume,
    /// Percent.
    EarconVolume,
    /// Percent.
    VoiceVolume,
    /// On or off.
    Hrtf,
    /// A key.
    TalkKey,
}

impl Setting {
    /// The menu's lines, in order.
    pub const ALL: [Setting; 7] = [
        Setting::SpeechRate,
        Setting::SpeechVolume,
        Setting::SoundVolume,
        Setting::EarconVolume,
        Setting::VoiceVolume,
        Setting::Hrtf,
        Setting::TalkKey,
    ];

    /// "Speech rate, 175 words a minute."
    pub fn spoken(self, s: &PlayerSettings) -> String {
        match self {
            Setting::SpeechRate => format!("Speech rate, {} words a minute.", s.speech_rate),
            Setting::SpeechVolume => format!("Speech volume, {} percent.", s.speech_volume),
            Setting::SoundVolume => format!("Sound volume, {} percent.", s.sound_volume),
            Setting::EarconVolume => format!("Earcon volume, {} percent.", s.earcon_volume),
            Setting::VoiceVolume => format!("Partner's voice volume, {} percent.", s.voice_volume),
            Setting::Hrtf => {
                format!("Sounds placed with the head model, HRTF: {}.", if s.hrtf { "on" } else { "off" })
            }
            Setting::TalkKey => format!("Push-to-talk key, {}.", s.talk_key.name()),
        }
    }

    /// Steps the setting up (`up`) or down, within its range; the talk key cycles through the choices.
    pub fn step(self, s: &mut PlayerSettings, up: bool) {
        let volume = |v: &mut u8| *v = if up { v.saturating_add(10).min(100) } else { v.saturating_sub(10) };
        match self {
            Setting::SpeechRate => {
                let (lo, hi) = SPEECH_RATE_RANGE;
                s.speech_rate =
                    if up { (s.speech_rate + 25).min(hi) } else { s.speech_rate.saturating_sub(25).max(lo) };
            }
            Setting::SpeechVolume => volume(&mut s.speech_volume),
            Setting::SoundVolume => volume(&mut s.sound_volume),
            Setting::EarconVolume => volume(&mut s.earcon_volume),
            Setting::VoiceVolume => volume(&mut s.voice_volume),
            Setting::Hrtf => s.hrtf = !s.hrtf,
            Setting::TalkKey => {
                let n = TalkKey::ALL.len();
                let at = TalkKey::ALL.iter().position(|k| *k == s.talk_key).unwrap_or(0);
                s.talk_key = TalkKey::ALL[if up { (at + 1) % n } else { (at + n - 1) % n }];
            }
        }
    }

    /// Copies this setting's value from `from` into `to` (so a change made in the menu reaches the file
    /// without the run's command-line overrides of the other settings).
    pub fn copy(self, from: &PlayerSettings, to: &mut PlayerSettings) {
        match self {
            Setting::SpeechRate => to.speech_rate = from.speech_rate,
            Setting::SpeechVolume => to.speech_volume = from.speech_volume,
            Setting::SoundVolume => to.sound_volume = from.sound_volume,
            Setting::EarconVolume => to.earcon_volume = from.earcon_volume,
            Setting::VoiceVolume => to.voice_volume = from.voice_volume,
            Setting::Hrtf => to.hrtf = from.hrtf,
            Setting::TalkKey => to.talk_key = from.talk_key,
        }
    }
}

/// A key press the menu understands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MenuKey {
    /// The previous setting.
    Up,
    /// The next setting.
    Down,
    /// Lower the setting.
    Left,
    /// Raise the setting.
    Right,
    /// Close and save.
    Close,
}

/// What the menu did with a key.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MenuOutcome {
    /// Say this.
    Say(String),
    /// The setting changed (apply it, then say this).
    Changed(Setting, String),
    /// The menu closed (save, then say what the caller adds).
    Closed,
}

/// The open menu: which setting was heard last.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SettingsMenu {
    at: usize,
}

/// What is said when the menu opens.
pub const OPENED: &str = "Settings. Up and down choose a setting, left and right change it, Enter closes.";

impl SettingsMenu {
    /// The setting heard last.
    pub fn current(&self) -> Setting {
        Setting::ALL[self.at % Setting::ALL.len()]
    }

    /// The lines said on opening: how it works, then the current setting.
    pub fn opening(&self, s: &PlayerSettings) -> [String; 2] {
        [OPENED.to_owned(), self.current().spoken(s)]
    }

    /// Handles one key; `s` are the settings in force (changed in place).
    pub fn press(&mut self, key: MenuKey, s: &mut PlayerSettings) -> MenuOutcome {
        let n = Setting::ALL.len();
        match key {
            MenuKey::Down => {
                self.at = (self.at + 1) % n;
                MenuOutcome::Say(self.current().spoken(s))
            }
            MenuKey::Up => {
                self.at = (self.at + n - 1) % n;
                MenuOutcome::Say(self.current().spoken(s))
            }
            MenuKey::Left | MenuKey::Right => {
                let setting = self.current();
                let before = *s;
                setting.step(s, key == MenuKey::Right);
                if *s == before {
                    let end = if key == MenuKey::Right { "highest" } else { "lowest" };
                    MenuOutcome::Say(format!("{} That is the {end}.", setting.spoken(s)))
                } else {
                    MenuOutcome::Changed(setting, setting.spoken(s))
                }
            }
            MenuKey::Close => MenuOutcome::Closed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn up_and_down_read_each_setting_with_its_value_and_wrap_around() {
        let mut menu = SettingsMenu::default();
        let mut s = PlayerSettings::default();
        assert_eq!(menu.opening(&s)[1], "Speech rate, 175 words a minute.");
        assert_eq!(menu.press(MenuKey::Down, &mut s), MenuOutcome::Say("Speech volume, 100 percent.".into()));
        assert_eq!(menu.press(MenuKey::Up, &mut s), MenuOutcome::Say("Speech rate, 175 words a minute.".into()));
        assert_eq!(menu.press(MenuKey::Up, &mut s), MenuOutcome::Say("Push-to-talk key, V.".into()));
    }

    #[test]
    fn left_and_right_change_the_setting_and_stop_at_its_ends() {
        let mut menu = SettingsMenu::default();
        let mut s = PlayerSettings::default();
        let out = menu.press(MenuKey::Right, &mut s);
        assert_eq!(out, MenuOutcome::Changed(Setting::SpeechRate, "Speech rate, 200 words a minute.".into()));
        menu.press(MenuKey::Down, &mut s);
        let out = menu.press(MenuKey::Right, &mut s);
        assert_eq!(out, MenuOutcome::Say("Speech volume, 100 percent. That is the highest.".into()));
        for _ in 0..12 {
            menu.press(MenuKey::Left, &mut s);
        }
        assert_eq!(s.speech_volume, 0);
        menu.press(MenuKey::Down, &mut s);
        menu.press(MenuKey::Down, &mut s);
        menu.press(MenuKey::Down, &mut s);
        menu.press(MenuKey::Down, &mut s);
        let out = menu.press(MenuKey::Left, &mut s);
        assert!(matches!(out, MenuOutcome::Changed(Setting::Hrtf, ref l) if l.ends_with("off.")), "{out:?}");
        menu.press(MenuKey::Down, &mut s);
        menu.press(MenuKey::Right, &mut s);
        assert_eq!(s.talk_key, TalkKey::T);
        assert_eq!(menu.press(MenuKey::Close, &mut s), MenuOutcome::Closed);
    }

    #[test]
    fn speech_rate_stays_within_what_espeak_takes() {
        let mut s = PlayerSettings { speech_rate: 390, ..Default::default() };
        Setting::SpeechRate.step(&mut s, true);
        assert_eq!(s.speech_rate, 400);
        let mut s = PlayerSettings { speech_rate: 90, ..Default::default() };
        Setting::SpeechRate.step(&mut s, false);
        assert_eq!(s.speech_rate, 80);
    }

    #[test]
    fn a_change_is_copied_to_the_file_without_the_other_settings_overrides() {
        let file = PlayerSettings::default();
        let mut run = PlayerSettings { hrtf: false, ..file };
        Setting::SpeechRate.step(&mut run, true);
        let mut saved = file;
        Setting::SpeechRate.copy(&run, &mut saved);
        assert_eq!(saved, PlayerSettings { speech_rate: 200, ..file }, "hrtf stays as the file had it");
    }
}
