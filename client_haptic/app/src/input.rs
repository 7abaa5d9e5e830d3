//! Phantom's input, read → decided → acted on. [`read_keys`] (and the client's `read_buttons`) turn the
//! keyboard (the terminal's typed lines press its keys too) and the device's buttons into a plain
//! [`PhantomInput`] each frame; [`decide`], a pure function, turns that input and where the game stands ([`Situation`])
//! into [`Action`]s; the client's small systems carry the actions out (`client.rs`).
//!
//! The keys: in the lobby, up and down read the menu and Enter chooses; after a result Enter asks for
//! another round; anytime Q leaves, R repeats, S says the status, B the briefing; during the heist H, G and
//! C warn Vive (hide, go, come back) and Y or N (or the device's first or second button) say whether the
//! copy on the bench is real; outside the lobby the arrows and page up/down move the simulated hand.

use bevy::input::ButtonInput;
use bevy::input::keyboard::KeyCode;
use bevy::prelude::*;
use glam::Vec3;
use heist_shared::protocol::{ItemId, Phase, WarningKind};

use crate::status::MenuItem;

/// A key Phantom presses, by what it asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// The menu's previous item (arrow up).
    MenuUp,
    /// The menu's next item (arrow down).
    MenuDown,
    /// Choose (Enter).
    Enter,
    /// Leave the session (Q).
    Leave,
    /// Say the last line again (R).
    Repeat,
    /// Say where the heist stands (S).
    Status,
    /// Say the briefing (B).
    Briefing,
    /// Warn Vive: hide (H).
    Hide,
    /// Warn Vive: go (G).
    Go,
    /// Warn Vive: come back (C).
    ComeBack,
    /// The copy is real (Y, or the device's first button).
    Real,
    /// The copy is fake (N, or the device's second button).
    Fake,
}

/// The keyboard's keys for each [`Key`].
pub const KEYMAP: [(KeyCode, Key); 12] = [
    (KeyCode::ArrowUp, Key::MenuUp),
    (KeyCode::ArrowDown, Key::MenuDown),
    (KeyCode::Enter, Key::Enter),
    (KeyCode::KeyQ, Key::Leave),
    (KeyCode::KeyR, Key::Repeat),
    (KeyCode::KeyS, Key::Status),
    (KeyCode::KeyB, Key::Briefing),
    (KeyCode::KeyH, Key::Hide),
    (KeyCode::KeyG, Key::Go),
    (KeyCode::KeyC, Key::ComeBack),
    (KeyCode::KeyY, Key::Real),
    (KeyCode::KeyN, Key::Fake),
];

/// The keys that move the simulated hand while held, and which way (scene frame: +x right, +y up, +z
/// towards the player).
pub const HAND_KEYS: [(KeyCode, Vec3); 6] = [
    (KeyCode::ArrowLeft, Vec3::NEG_X),
    (KeyCode::ArrowRight, Vec3::X),
    (KeyCode::ArrowUp, Vec3::NEG_Z),
    (KeyCode::ArrowDown, Vec3::Z),
    (KeyCode::PageUp, Vec3::Y),
    (KeyCode::PageDown, Vec3::NEG_Y),
];

/// This frame's input: the keys pressed (once each) and where the held keys push the hand.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq)]
pub struct PhantomInput {
    pressed: u16,
    /// Where the held arrow and page keys push the simulated hand: a sum of unit axes.
    pub hand: Vec3,
}

impl PhantomInput {
    /// Input with `keys` pressed and the hand still.
    pub fn with(keys: &[Key]) -> Self {
        let mut input = Self::default();
        keys.iter().for_each(|k| input.press(*k));
        input
    }

    /// Presses `key` for this frame.
    pub fn press(&mut self, key: Key) {
        self.pressed |= 1 << key as u16;
    }

    /// Whether `key` was pressed this frame.
    pub fn pressed(&self, key: Key) -> bool {
        self.pressed & (1 << key as u16) != 0
    }
}

/// Where the game stands, as far as the keys care.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Situation {
    /// The session's phase.
    pub phase: Phase,
    /// The menu item read last.
    pub menu_item: usize,
    /// Ready was already sent.
    pub ready_sent: bool,
    /// The copy held on the bench, feelable now.
    pub held_copy: Option<ItemId>,
    /// The touch bot explores (it steers the hand).
    pub exploring: bool,
}

/// What Phantom's input asks for.
#[derive(Message, Clone, Copy, Debug, PartialEq)]
pub enum Action {
    /// Read this menu item (it becomes the menu's current one).
    ReadMenu(usize),
    /// Tell the server Phantom is ready.
    Ready,
    /// Say this line.
    Say(&'static str),
    /// Say where the heist stands.
    SayStatus,
    /// Say the briefing.
    SayBriefing,
    /// Say the keys.
    SayHelp,
    /// Open the settings menu.
    OpenSettings,
    /// Ask for another round.
    Rematch,
    /// Leave the session.
    Leave,
    /// Say the last line again.
    Repeat,
    /// Warn Vive.
    Warn(WarningKind),
    /// Say whether the copy is real.
    Verdict {
        /// The copy.
        item: ItemId,
        /// Declared real.
        real: bool,
    },
    /// Move the simulated hand this way (a sum of unit axes) this frame.
    MoveHand(Vec3),
}

/// What `input` asks for in `situation`, in the order it is carried out.
pub fn decide(input: &PhantomInput, situation: &Situation) -> Vec<Action> {
    let mut actions = Vec::new();
    let phase = situation.phase;
    if phase == Phase::Lobby {
        let n = MenuItem::ALL.len();
        let mut item = situation.menu_item % n;
        if input.pressed(Key::MenuDown) {
            item = (item + 1) % n;
            actions.push(Action::ReadMenu(item));
        }
        if input.pressed(Key::MenuUp) {
            item = (item + n - 1) % n;
            actions.push(Action::ReadMenu(item));
        }
        if input.pressed(Key::Enter) {
            actions.push(match MenuItem::ALL[item] {
                MenuItem::Ready if !situation.ready_sent => Action::Ready,
                MenuItem::Ready => Action::Say("You are ready. Waiting for Vive."),
                MenuItem::Briefing => Action::Say("The briefing comes when the heist begins."),
                MenuItem::Status => Action::SayStatus,
                MenuItem::Settings => Action::OpenSettings,
                MenuItem::Help => Action::SayHelp,
            });
        }
    }
    if matches!(phase, Phase::Won | Phase::Lost(_)) && input.pressed(Key::Enter) {
        actions.push(Action::Rematch);
    }
    for (key, action) in [
        (Key::Leave, Action::Leave),
        (Key::Repeat, Action::Repeat),
        (Key::Status, Action::SayStatus),
        (Key::Briefing, Action::SayBriefing),
    ] {
        if input.pressed(key) {
            actions.push(action);
        }
    }
    if phase == Phase::Heist {
        for (key, warning) in
            [(Key::Hide, WarningKind::Hide), (Key::Go, WarningKind::Go), (Key::ComeBack, WarningKind::ComeBack)]
        {
            if input.pressed(key) {
                actions.push(Action::Warn(warning));
            }
        }
        if let Some(item) = situation.held_copy {
            for (key, real) in [(Key::Real, true), (Key::Fake, false)] {
                if input.pressed(key) {
                    actions.push(Action::Verdict { item, real });
                }
            }
        }
    }
    if phase != Phase::Lobby && input.hand != Vec3::ZERO && !situation.exploring {
        actions.push(Action::MoveHand(input.hand));
    }
    actions
}

/// Reads the keyboard (or the terminal's typed lines) into this frame's [`PhantomInput`]; nothing while
/// the settings menu has the keys.
pub fn read_keys(
    keys: Option<Res<ButtonInput<KeyCode>>>,
    prefs: Res<crate::settings::plugin::Settings>,
    mut input: ResMut<PhantomInput>,
) {
    *input = PhantomInput::default();
    let Some(keys) = keys.filter(|_| !prefs.is_open()) else { return };
    for (code, key) in KEYMAP {
        if keys.just_pressed(code) {
            input.press(key);
        }
    }
    input.hand = HAND_KEYS.iter().filter(|(code, _)| keys.pressed(*code)).map(|(_, d)| *d).sum();
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lobby(menu_item: usize) -> Situation {
        Situation { phase: Phase::Lobby, menu_item, ready_sent: false, held_copy: None, exploring: false }
    }

    fn heist(held_copy: Option<ItemId>) -> Situation {
        Situation { phase: Phase::Heist, held_copy, ..lobby(0) }
    }

    #[test]
    fn in_the_lobby_down_reads_the_next_menu_item_and_up_the_one_before_wrapping_round() {
        assert_eq!(decide(&PhantomInput::with(&[Key::MenuDown]), &lobby(0)), [Action::ReadMenu(1)]);
        assert_eq!(decide(&PhantomInput::with(&[Key::MenuUp]), &lobby(0)), [Action::ReadMenu(MenuItem::ALL.len() - 1)]);
        assert_eq!(
            decide(&PhantomInput::with(&[Key::MenuDown]), &lobby(MenuItem::ALL.len() - 1)),
            [Action::ReadMenu(0)]
        );
    }

    #[test]
    fn enter_on_ready_sends_ready_once_and_then_only_says_so() {
        assert_eq!(decide(&PhantomInput::with(&[Key::Enter]), &lobby(0)), [Action::Ready]);
        let ready = Situation { ready_sent: true, ..lobby(0) };
        assert_eq!(
            decide(&PhantomInput::with(&[Key::Enter]), &ready),
            [Action::Say("You are ready. Waiting for Vive.")]
        );
    }

    #[test]
    fn enter_chooses_the_item_just_read_not_the_one_before() {
        let settings = MenuItem::ALL.iter().position(|m| *m == MenuItem::Settings).expect("a settings item");
        let input = PhantomInput::with(&[Key::MenuDown, Key::Enter]);
        assert_eq!(decide(&input, &lobby(settings - 1)), [Action::ReadMenu(settings), Action::OpenSettings]);
    }

    #[test]
    fn after_a_result_enter_asks_for_another_round_and_during_the_heist_it_does_nothing() {
        let won = Situation { phase: Phase::Won, ..lobby(0) };
        assert_eq!(decide(&PhantomInput::with(&[Key::Enter]), &won), [Action::Rematch]);
        assert!(decide(&PhantomInput::with(&[Key::Enter]), &heist(None)).is_empty());
    }

    #[test]
    fn y_and_n_judge_the_copy_only_when_one_is_held_on_the_bench_during_the_heist() {
        let copy = ItemId(7);
        assert_eq!(
            decide(&PhantomInput::with(&[Key::Real]), &heist(Some(copy))),
            [Action::Verdict { item: copy, real: true }]
        );
        assert_eq!(
            decide(&PhantomInput::with(&[Key::Fake]), &heist(Some(copy))),
            [Action::Verdict { item: copy, real: false }]
        );
        assert!(decide(&PhantomInput::with(&[Key::Real]), &heist(None)).is_empty(), "no copy held");
        let lobby_with_copy = Situation { held_copy: Some(copy), ..lobby(0) };
        assert!(decide(&PhantomInput::with(&[Key::Real]), &lobby_with_copy).is_empty(), "not during the heist");
    }

    #[test]
    fn warnings_go_to_vive_during_the_heist_only() {
        let input = PhantomInput::with(&[Key::Hide, Key::Go, Key::ComeBack]);
        let warnings = [WarningKind::Hide, WarningKind::Go, WarningKind::ComeBack].map(Action::Warn);
        assert_eq!(decide(&input, &heist(None)), warnings);
        assert!(decide(&input, &lobby(0)).is_empty());
    }

    #[test]
    fn leave_repeat_status_and_briefing_work_in_every_phase() {
        let input = PhantomInput::with(&[Key::Leave, Key::Repeat, Key::Status, Key::Briefing]);
        let all = [Action::Leave, Action::Repeat, Action::SayStatus, Action::SayBriefing];
        assert_eq!(decide(&input, &lobby(0)), all);
        assert_eq!(decide(&input, &heist(None)), all);
    }

    #[test]
    fn the_held_keys_move_the_hand_outside_the_lobby_unless_the_touch_bot_steers_it() {
        let input = PhantomInput { hand: Vec3::new(1.0, 0.0, -1.0), ..Default::default() };
        assert_eq!(decide(&input, &heist(None)), [Action::MoveHand(Vec3::new(1.0, 0.0, -1.0))]);
        assert!(decide(&input, &lobby(0)).is_empty(), "the arrows read the menu there");
        assert!(decide(&input, &Situation { exploring: true, ..heist(None) }).is_empty());
    }

    #[test]
    fn a_key_is_pressed_once_and_no_other_with_it() {
        let input = PhantomInput::with(&[Key::Status]);
        assert!(input.pressed(Key::Status));
        assert!(KEYMAP.iter().filter(|(_, k)| *k != Key::Status).all(|(_, k)| !input.pressed(*k)));
    }
}
