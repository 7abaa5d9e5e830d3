//! Keys from the terminal for `--headless` play (no window to take the keyboard): each line typed
//! presses the matching key for one frame, so a screen-reader user can play from a console.
//!
//! Lines: `y`, `n` (verdict), `s` (status), `b` (briefing), `r` (repeat), `h`, `g`, `c` (warn Vive),
//! `up`, `down`, and an empty line or `enter` (menu).

use std::sync::Mutex;
use std::sync::mpsc::Receiver;

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
        "" | "enter" | "ready" | "again" | "another round" => KeyCode::Enter,
        _ => return None,
    })
}

/// What is said when a typed line is no key.
const HELP: &str = "Type y, n, s, b, r, h, g, c, q, up, down, or just Enter.";

#[derive(Resource)]
struct Lines(Mutex<Receiver<String>>);

/// Reads stdin on a thread and presses keys.
pub struct TerminalKeysPlugin;

impl Plugin for TerminalKeysPlugin {
    fn build(&self, app: &mut App) {
        let (tx, rx) = std::sync::mpsc::channel();
        let spawned = std::thread::Builder::new().name("terminal-keys".into()).spawn(move || {
            for line in std::io::stdin().lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        if let Err(e) = spawned {
            log::error!("no terminal keys: {e}");
        }
        app.init_resource::<ButtonInput<KeyCode>>()
            .insert_resource(Lines(Mutex::new(rx)))
            .add_systems(PreUpdate, press);
    }
}

fn press(mut keys: ResMut<ButtonInput<KeyCode>>, lines: Res<Lines>, mut speaker: Option<NonSendMut<Speaker>>) {
    keys.release_all();
    keys.clear();
    let rx = lines.0.lock().unwrap_or_else(|p| p.into_inner());
    while let Ok(line) = rx.try_recv() {
        match key_for(&line) {
            Some(k) => keys.press(k),
            None => match speaker.as_mut() {
                Some(s) => s.say(HELP),
                None => println!("{HELP}"),
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
