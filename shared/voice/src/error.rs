//! What can go wrong with the walkie-talkie, said so a player can act on it.

use thiserror::Error;

/// An error of the voice path (none of them stops the game: the walkie-talkie is then silent).
#[derive(Debug, Error)]
pub enum VoiceError {
    /// The Opus codec refused (a bug, or a corrupt packet).
    #[error("opus: {0}")]
    Codec(String),
    /// The WAV file given as the microphone cannot be used.
    #[error("the microphone file {path}: {why}")]
    MicFile {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        why: String,
    },
    /// No microphone could be opened.
    #[error("no microphone: {0}")]
    NoMicrophone(String),
    /// The voice could not be played.
    #[error("voice playback: {0}")]
    Playback(String),
}

impl From<opus::Error> for VoiceError {
    fn from(e: opus::Error) -> Self {
        VoiceError::Codec(e.to_string())
    }
}
