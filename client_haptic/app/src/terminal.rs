//! Keys from the terminal for `--headless` play (no window to take the keyboard): each line typed
//! presses the matching key for one frame, so a screen-reader user can play from a console.
//!
//! Lines: `y`, `n` (verdict), `s` (status), `b` (briefing), `r` (repeat), `h`, `g`, `c` (warn Vive),
//! `o` (settings), `talk` and `over` (the walkie-talkie: a line cannot be held, so `talk` holds the
//! push-to-talk key down until `over`), `up`, `down`, `left`, `right`, and an empty line or `enter` (menu).

use std::sync::mpsc::Receiver;
use std::sync::{Mutex, OnceLock};

use bevy::input::ButtonInput;
use bevy::input::keyboard::KeyCode;
use bevy::prelude::*;

use crate::speech::Speaker;

/// The key a typed line stands for.
pub fn key_for(line: &str) -> Option<KeyCode> {
    Some(match line.trim().to_ascii_lowercase().as_str() {
        "y" | "yes" | "real" => KeyCode::KeyY,
        "n" | "no" | "fake" => KeyCode::KeyN,
        "s" | "status" => KeyCode::KeyS,
        "b" | "briefing" => KeyCode::KeyB,
        "r" | "repeat" => KeyCode::KeyR,
        "h" | "hide" => KeyCode::KeyH,
        "g" | "go" => KeyCode::KeyG,
        "c" | "come back" => KeyCode::KeyC,
        "q" | "quit" | "leave" => KeyCode::KeyQ,
        "up" => KeyCode::ArrowUp,
        "down" => KeyCode::ArrowDown,
        "left" => KeyCode::ArrowLeft,
        "right" => KeyCode::ArrowRight,
        "o" | "settings" | "options" => KeyCode::KeyO,
        "escape" | "esc" | "done" => KeyCode::Escape,
        "" | "enter" | "ready" | "again" | "another round" => KeyCode::Enter,
        _ => return None,
    })
}

/// What is said when a typed line is no key.
const HELP: &str = "Type y, n, s, b, r, h, g, c, o, q, talk, over, up, down, left, right, or just Enter.";

/// What stdin brings, byte by byte (`None`: it ended), from one reader thread for the whole process:
/// the spoken prompts before joining read it a character at a time, the game's keys a line at a time,
/// and neither may lose what the other did not take.
pub fn stdin_bytes() -> &'static Mutex<Receiver<Option<u8>>> {
    static INPUT: OnceLock<Mutex<Receiver<Option<u8>>>> = OnceLock::new();
    INPUT.get_or_init(|| {
        let (tx, rx) = std::sync::mpsc::channel();
        let spawned = std::thread::Builder::new().name("stdin".into()).spawn(move || {
            use std::io::Read as _;
            let mut buf = [0u8; 256];
            let mut stdin = std::io::stdin();
            loop {
                match stdin.read(&mut buf) {
                    Ok(0) | Err(_) => {
                        let _ = tx.send(None);
                        break;
                    }
                    Ok(n) => {
                        if buf[..n].iter().any(|b| tx.send(Some(*b)).is_err()) {
                            break;
                        }
                    }
                }
            }
        });
        if let Err(e) = spawned {
            log::error!("no terminal input: {e}");
        }
        Mutex::new(rx)
    })
}

/// The line being typed, the lines not yet acted on, and whether `talk` holds the push-to-talk key down.
#[derive(Resource, Default)]
pub struct TerminalInput {
    partial: Vec<u8>,
    /// Typed lines waiting: one is acted on per frame, so lines typed (or pasted) together press their
    /// keys one after the other, not at once (two `down`s in one frame would move the menu once).
    waiting: std::collections::VecDeque<String>,
    /// `talk` was typed and `over` not yet: the walkie-talkie transmits.
    pub talking: bool,
}

/// Reads stdin's lines and presses keys.
pub struct TerminalKeysPlugin;

impl Plugin for TerminalKeysPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ButtonInput<KeyCode>>().init_resource::<TerminalInput>().add_systems(PreUpdate, press);
    }
}

fn press(
    mut keys: ResMut<ButtonInput<KeyCode>>,
    mut input: ResMut<TerminalInput>,
    mut speaker: Option<NonSendMut<Speaker>>,
) {
    keys.release_all();
    keys.clear();
    {
        let rx = stdin_bytes().lock().unwrap_or_else(|p| p.into_inner());
        while let Ok(Some(b)) = rx.try_recv() {
            match b {
                b'\n' => {
                    let line = String::from_utf8_lossy(&std::mem::take(&mut input.partial)).into_owned();
                    if input.waiting.len() < 64 {
                        input.waiting.push_back(line);
                    }
                }
                b'\r' => {}
                _ if input.partial.len() < 1024 => input.partial.push(b),
                _ => {}
            }
        }
    }
    if let Some(line) = input.waiting.pop_front() {
        match line.trim().to_ascii_lowercase().as_str() {
            "talk" => input.talking = true,
            "over" => input.talking = false,
            _ => match key_for(&line) {
                Some(k) => keys.press(k),
                None => match speaker.as_mut() {
                    Some(s) => s.say(HELP),
                    None => println!("{HELP}"),
                },
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typed_words_map_to_the_game_keys() {
        assert_eq!(key_for("Y"), Some(KeyCode::KeyY));
        assert_eq!(key_for(" fake "), Some(KeyCode::KeyN));
        assert_eq!(key_for(""), Some(KeyCode::Enter));
        assert_eq!(key_for("status"), Some(KeyCode::KeyS));
        assert_eq!(key_for("xyzzy"), None);
    }
}
