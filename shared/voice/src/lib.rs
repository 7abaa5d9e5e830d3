//! The walkie-talkie between the two thieves: push-to-talk voice from one client, through the server, to
//! the other.
//!
//! You need this crate to talk or to hear the partner. The path of a voice, and the module of each step:
//! - [`mic`]: the microphone (cpal with the `mic` feature, or a WAV file for tests and headless runs),
//!   resampled to 48 kHz mono;
//! - [`tx`]: push-to-talk gating and 20 ms framing into Opus packets ([`codec`]) with in-band FEC;
//! - over the network as [`heist_shared::protocol::voice`] frames on their own unreliable channel, relayed
//!   by the server to the partner only;
//! - [`jitter`]: the receiver's jitter buffer (playout delay that adapts to late frames, FEC recovery and
//!   loss concealment);
//! - [`playback`]: a kira sound that pulls frames from the jitter buffer and decodes them on the audio
//!   thread, so the playout clock is the sound card's (no allocation, lock or log there);
//! - [`plugin`]: the Bevy plugin both clients add ([`VoicePlugin`]), steered by the [`Talk`] resource;
//! - [`measure`]: envelopes and alignment, to measure a voice path end to end.
#![warn(missing_docs)]

pub mod codec;
mod error;
pub mod jitter;
pub mod measure;
pub mod mic;
pub mod playback;
pub mod plugin;
pub mod tx;

pub use error::VoiceError;
pub use plugin::{HeardVoice, MicChoice, Talk, TalkMode, VoiceFlags, VoicePlugin, VoiceSettings, VoiceSystems};

pub use heist_shared::protocol::voice::{MAX_VOICE_BYTES, VOICE_FRAME_SAMPLES, VOICE_SAMPLE_RATE};

/// The Opus bit rate the clients send, bits per second (speech is clear from 16 kb/s; the issue's
/// ceiling is 32).
pub const BITRATE: i32 = 24_000;
/// The packet loss the encoder prepares its in-band FEC for, percent.
pub const EXPECTED_LOSS_PERCENT: i32 = 10;
