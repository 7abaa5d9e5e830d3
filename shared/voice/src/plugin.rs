//! The walkie-talkie in a client app. The app says whether push-to-talk is down ([`Talk`]); the plugin
//! sends the microphone's frames while it is, plays the partner's frames on the audio engine's partner
//! voice (the app places it), and tells the app what to announce ([`HeardVoice`]).
//!
//! Systems: [`VoiceSystems::Receive`] in `PreUpdate` (after replicon's receive: the partner's frames to
//! the audio thread), [`VoiceSystems::Send`] in `PostUpdate` (before replicon's send: this frame's voice
//! frames out). Add it after the client core (`heist_client::ClientNetPlugin`) and the audio engine.

use std::path::PathBuf;

use bevy::prelude::*;
use bevy_replicon::prelude::ClientSystems;
use heist_audio::AudioEngine;
use heist_shared::protocol::voice::{ClientVoice, PartnerVoice, VoiceFrame};

use crate::mic::{Microphone, WavMic};
use crate::playback::{VoiceHandle, VoiceSoundData};
use crate::tx::{TalkChange, Transmitter};

/// Where this client's voice comes from.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum MicChoice {
    /// The system's default microphone (the `mic` feature; without it, none).
    #[default]
    Device,
    /// A WAV file, said from its start at each transmission (`--mic-wav FILE`).
    Wav(PathBuf),
    /// No microphone: the walkie-talkie only listens.
    Off,
}

/// When this client transmits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TalkMode {
    /// While [`Talk::down`].
    #[default]
    PushToTalk,
    /// From the start: a microphone file is said once as soon as the client runs, then the
    /// transmission ends; a device stays open (bots, tests, hands-free play).
    Open,
}

/// The walkie-talkie's settings.
#[derive(Resource, Clone, Debug, Default)]
pub struct VoiceSettings {
    /// The microphone.
    pub mic: MicChoice,
    /// When to transmit.
    pub mode: TalkMode,
}

/// The walkie-talkie's command-line flags, the same in both clients (`clap` with the `cli` feature).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct VoiceFlags {
    /// A WAV file as the walkie-talkie's microphone: each transmission says it from its start.
    #[cfg_attr(feature = "cli", arg(long, conflicts_with = "no_mic"))]
    pub mic_wav: Option<PathBuf>,
    /// No microphone: the walkie-talkie only listens (also when there is no sound card, unless --mic-wav).
    #[cfg_attr(feature = "cli", arg(long))]
    pub no_mic: bool,
    /// Transmit from the start without push-to-talk (with --mic-wav: say the file once, then stop).
    #[cfg_attr(feature = "cli", arg(long))]
    pub open_mic: bool,
}

impl VoiceFlags {
    /// The settings these flags ask for; `sound_card` says whether the client plays on a sound card
    /// (without one there is no microphone either, unless a file is given).
    pub fn settings(&self, sound_card: bool) -> VoiceSettings {
        VoiceSettings {
            mic: match (&self.mic_wav, self.no_mic || !sound_card) {
                (Some(path), _) => MicChoice::Wav(path.clone()),
                (None, true) => MicChoice::Off,
                (None, false) => MicChoice::Device,
            },
            mode: if self.open_mic { TalkMode::Open } else { TalkMode::PushToTalk },
        }
    }
}

/// Push-to-talk, as the app's input systems set it each frame.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Talk {
    /// The key (button, typed `talk`) is down.
    pub down: bool,
}

/// What the player should hear of the walkie-talkie (the app plays the squelch and says the words).
#[derive(Message, Clone, Debug, PartialEq, Eq)]
pub enum HeardVoice {
    /// This client started transmitting.
    TalkStarted,
    /// This client stopped transmitting.
    TalkStopped,
    /// The partner started a transmission.
    PartnerStarted,
    /// The partner's transmission ended.
    PartnerStopped,
    /// Push-to-talk was pressed but there is no microphone (why).
    NoMicrophone(String),
}

/// System sets of the walkie-talkie.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum VoiceSystems {
    /// `PreUpdate`, after replicon's receive: the partner's frames to the audio thread.
    Receive,
    /// `PostUpdate`, before replicon's send: this frame's voice frames out.
    Send,
}

/// The walkie-talkie's state: the sending side (when there is a microphone) and the partner's voice
/// (when there is an audio engine). Not `Send`: it lives with the audio engine on the main thread.
pub struct Voice {
    /// The sending side.
    pub tx: Result<Transmitter, String>,
    /// The partner's voice on the audio engine.
    pub rx: Option<VoiceHandle>,
    /// Frames received from the partner.
    pub received: u64,
    /// The partner's last frame number and when it came (app time, s).
    partner_last: Option<(u16, f64)>,
    told_no_mic: bool,
    /// Frames written for sending this frame (kept to reuse its memory).
    outbox: Vec<VoiceFrame>,
}

/// Seconds of the partner's silence after which a transmission whose end frame was lost counts as over.
const PARTNER_QUIET_S: f64 = 0.5;

/// Adds the walkie-talkie (see the module docs).
pub struct VoicePlugin;

impl Plugin for VoicePlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<VoiceSettings>()
            .init_resource::<Talk>()
            .add_message::<HeardVoice>()
            .configure_sets(PreUpdate, VoiceSystems::Receive.after(ClientSystems::Receive))
            .configure_sets(PostUpdate, VoiceSystems::Send.before(ClientSystems::Send))
            .add_systems(Startup, open)
            .add_systems(PreUpdate, receive.in_set(VoiceSystems::Receive))
            .add_systems(PostUpdate, send.in_set(VoiceSystems::Send));
    }
}

/// Opens the microphone and starts the partner's voice on the audio engine.
fn open(world: &mut World) {
    let settings = world.get_resource::<VoiceSettings>().cloned().unwrap_or_default();
    let mic = match &settings.mic {
        MicChoice::Wav(path) => WavMic::open(path).map(Microphone::Wav).map_err(|e| e.to_string()),
        MicChoice::Off => Err("the microphone is off".to_owned()),
        #[cfg(feature = "mic")]
        MicChoice::Device => crate::mic::CpalMic::open().map(Microphone::Device).map_err(|e| e.to_string()),
        #[cfg(not(feature = "mic"))]
        MicChoice::Device => Err("built without the microphone (feature `mic`)".to_owned()),
    };
    if let Err(e) = &mic {
        log::info!("walkie-talkie: {e}; it only listens");
    }
    let tx = mic.and_then(|m| Transmitter::new(m).map_err(|e| e.to_string()));
    let rx = world
        .get_non_send_mut::<AudioEngine>()
        .and_then(|mut audio| audio.play_partner(VoiceSoundData).map_err(|e| log::warn!("walkie-talkie: {e}")).ok());
    world.insert_non_send(Voice {
        tx,
        rx,
        received: 0,
        partner_last: None,
        told_no_mic: false,
        outbox: Vec::with_capacity(crate::tx::MAX_BACKLOG_FRAMES + 1),
    });
}

/// The partner's frames to the audio thread; the start and end of the partner's transmissions.
fn receive(
    mut frames: MessageReader<PartnerVoice>,
    voice: Option<NonSendMut<Voice>>,
    time: Res<Time<Real>>,
    mut heard: MessageWriter<HeardVoice>,
) {
    let Some(mut voice) = voice else { return };
    let now = time.elapsed_secs_f64();
    for PartnerVoice(frame) in frames.read() {
        voice.received += 1;
        // A frame that does not follow the last one (or follows a silence) starts a transmission.
        let follows =
            voice.partner_last.is_some_and(|(seq, at)| frame.seq.wrapping_sub(seq) < 32 && now - at < PARTNER_QUIET_S);
        if !follows {
            heard.write(HeardVoice::PartnerStarted);
        }
        voice.partner_last = (!frame.end).then_some((frame.seq, now));
        if frame.end {
            heard.write(HeardVoice::PartnerStopped);
        }
        if let Some(rx) = voice.rx.as_mut() {
            rx.push(frame);
        }
    }
    if voice.partner_last.is_some_and(|(_, at)| now - at >= PARTNER_QUIET_S) {
        voice.partner_last = None;
        heard.write(HeardVoice::PartnerStopped);
    }
}

/// This frame's voice frames out, while push-to-talk is down (or the microphone is open).
fn send(
    voice: Option<NonSendMut<Voice>>,
    inbox: Option<Res<heist_client::Inbox>>,
    talk: Res<Talk>,
    settings: Res<VoiceSettings>,
    time: Res<Time<Real>>,
    mut out: MessageWriter<ClientVoice>,
    mut heard: MessageWriter<HeardVoice>,
) {
    let Some(mut voice) = voice else { return };
    let voice = &mut *voice;
    // Until the server has welcomed this client, nothing it sends would be relayed.
    let welcomed = inbox.is_some_and(|i| i.role.is_some());
    let open = settings.mode == TalkMode::Open && !voice.tx.as_ref().is_ok_and(|tx| tx.said_all());
    let down = (talk.down || open) && welcomed;
    let tx = match voice.tx.as_mut() {
        Ok(tx) => tx,
        Err(why) => {
            if talk.down && !voice.told_no_mic {
                voice.told_no_mic = true;
                heard.write(HeardVoice::NoMicrophone(why.clone()));
            }
            return;
        }
    };
    voice.outbox.clear();
    match tx.step(down, time.elapsed_secs_f64(), &mut voice.outbox) {
        Some(TalkChange::Started) => {
            heard.write(HeardVoice::TalkStarted);
        }
        Some(TalkChange::Stopped) => {
            heard.write(HeardVoice::TalkStopped);
        }
        None => {}
    }
    for frame in voice.outbox.drain(..) {
        out.write(ClientVoice::Frame(frame));
    }
}
