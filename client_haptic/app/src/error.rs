//! What can go wrong in the Phantom client, said so a player can act on it.

use thiserror::Error;

/// An error of the Phantom client.
#[derive(Debug, Error)]
pub enum ClientError {
    /// The haptic device could not be opened or used.
    #[error("haptic device: {0}")]
    Device(String),
    /// The haptic loop could not start.
    #[error("haptic loop: {0}")]
    Rig(#[from] haptic_rig::RigError),
    /// A copy's mesh could not become a sphere tree.
    #[error("copy {item}: {reason}")]
    Copy {
        /// The copy.
        item: u32,
        /// Why.
        reason: String,
    },
    /// Audio could not start.
    #[error(transparent)]
    Audio(#[from] heist_audio::AudioError),
    /// Speech could not be synthesized.
    #[error("speech: {0}")]
    Speech(String),
    /// Joining the session failed.
    #[error("joining: {0}")]
    Join(#[from] heist_client::JoinError),
}
