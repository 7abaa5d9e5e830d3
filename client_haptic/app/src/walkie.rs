//! Phantom's walkie-talkie: the push-to-talk key from the settings (or the device's third button, or
//! `talk` typed in the terminal until `over`), a squelch on pressing and releasing, and Vive's voice
//! placed where Vive is in the museum relative to the workbench, so the voice itself says where the
//! partner is.
//!
//! You need this module to change how Phantom talks or hears Vive; the voice path itself is
//! `heist_voice`.

use bevy::input::ButtonInput;
use bevy::input::keyboard::KeyCode;
use bevy::prelude::*;
use heist_client::Inbox;
use heist_shared::protocol::ViveAvatar;
use heist_voice::{HeardVoice, Talk};

use crate::audio::synth::{self, Earcon};
use crate::audio::{AudioEngine, listener_offset};
use crate::settings::plugin::Settings;
use crate::speech::Speaker;

/// Height of Vive's mouth above the floor, m.
pub const MOUTH_HEIGHT_M: f32 = 1.6;

/// The device button that talks (the third; the first two say real and fake).
pub const TALK_BUTTON: u32 = 1 << 2;

/// Phantom's side of the walkie-talkie (add after `heist_voice::VoicePlugin`).
pub struct WalkiePlugin;

impl Plugin for WalkiePlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(
            Update,
            (push_to_talk, place_vives_voice, tell_the_walkie).chain().in_set(crate::schedule::PhantomSystems::Sound),
        );
    }
}

/// Push-to-talk is down while the talk key or the device's talk button is held, or after `talk` was typed.
fn push_to_talk(
    keys: Option<Res<ButtonInput<KeyCode>>>,
    terminal: Option<Res<crate::terminal::TerminalInput>>,
    settings: Res<Settings>,
    frame: Res<bevy_haptics::HapticFrame>,
    mut talk: ResMut<Talk>,
) {
    let key = keys.is_some_and(|k| k.pressed(settings.run.talk_key.key_code())) && !settings.is_open();
    let typed = terminal.is_some_and(|t| t.talking);
    let button = frame.pressed(TALK_BUTTON);
    let down = key || typed || button;
    if talk.down != down {
        talk.down = down;
    }
}

/// Vive's voice comes from where Vive stands, heard from the workbench.
fn place_vives_voice(inbox: Res<Inbox>, vive: Query<&ViveAvatar>, mut audio: NonSendMut<AudioEngine>) {
    let (Some(level), Some(v)) = (inbox.level.as_ref(), vive.iter().next()) else { return };
    audio.place_partner(listener_offset(level.workbench, v.position, MOUTH_HEIGHT_M));
}

/// Squelches and what is said about the walkie-talkie.
fn tell_the_walkie(
    mut heard: MessageReader<HeardVoice>,
    mut audio: NonSendMut<AudioEngine>,
    mut speaker: NonSendMut<Speaker>,
) {
    for h in heard.read() {
        match h {
            HeardVoice::TalkStarted => {
                audio.earcon(Earcon::SquelchOpen);
                speaker.print("Talking to Vive.");
            }
            HeardVoice::TalkStopped => {
                audio.earcon(Earcon::SquelchClose);
                speaker.print("Over.");
            }
            // Vive's squelch comes from where Vive is, like the voice.
            HeardVoice::PartnerStarted => {
                let _ = audio.play_partner(synth::earcon(Earcon::SquelchOpen));
            }
            HeardVoice::PartnerStopped => {
                let _ = audio.play_partner(synth::earcon(Earcon::SquelchClose));
            }
            HeardVoice::NoMicrophone(why) => {
                speaker.say(format!("The walkie-talkie has no microphone ({why}). You can still hear Vive."))
            }
        }
    }
}
