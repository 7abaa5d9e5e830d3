//! Vive's walkie-talkie: V held on the desktop (a talk button in XR: `xr`), the squelch on pressing
//! and releasing, Phantom's voice from the radio on Vive's shoulder, and the HUD saying who talks.
//!
//! You need this module to change how Vive talks or hears Phantom; the voice path itself is
//! `heist_voice`.

use bevy::input::ButtonInput;
use bevy::input::keyboard::KeyCode;
use bevy::prelude::*;
use heist_audio::AudioEngine;
use heist_audio::synth::{self, Earcon};
use heist_voice::{HeardVoice, Talk};

use crate::client::{ViveState, ViveSystems};
use crate::intent::InputSource;

/// The desktop's push-to-talk key.
pub const TALK_KEY: KeyCode = KeyCode::KeyV;

/// Vive's side of the walkie-talkie (add after `heist_voice::VoicePlugin`).
pub struct WalkiePlugin;

impl Plugin for WalkiePlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, (push_to_talk, tell_the_walkie).chain().in_set(ViveSystems::Present));
    }
}

/// On the desktop, push-to-talk is down while V is held (XR sets it from the controller).
fn push_to_talk(keys: Option<Res<ButtonInput<KeyCode>>>, input: Res<InputSource>, mut talk: ResMut<Talk>) {
    if *input != InputSource::Desktop {
        return;
    }
    let down = keys.is_some_and(|k| k.pressed(TALK_KEY));
    if talk.down != down {
        talk.down = down;
    }
}

/// Squelches (when there is sound) and the HUD's lines.
fn tell_the_walkie(
    mut heard: MessageReader<HeardVoice>,
    audio: Option<NonSendMut<AudioEngine>>,
    mut state: ResMut<ViveState>,
    time: Res<Time>,
) {
    let mut audio = audio;
    let now = time.elapsed_secs_f64();
    for h in heard.read() {
        let (line, earcon) = match h {
            HeardVoice::TalkStarted => (Some("Talking to Phantom...".to_owned()), Some((Earcon::SquelchOpen, false))),
            HeardVoice::TalkStopped => (None, Some((Earcon::SquelchClose, false))),
            HeardVoice::PartnerStarted => (Some("Phantom is talking".to_owned()), Some((Earcon::SquelchOpen, true))),
            HeardVoice::PartnerStopped => (None, Some((Earcon::SquelchClose, true))),
            HeardVoice::NoMicrophone(why) => (Some(format!("No microphone ({why}): you can only listen")), None),
        };
        if let Some(line) = line {
            state.say(now, line);
        }
        if let (Some(audio), Some((e, partner))) = (audio.as_mut(), earcon) {
            if partner {
                let _ = audio.play_partner(synth::earcon(e));
            } else {
                audio.earcon(e);
            }
        }
    }
}
