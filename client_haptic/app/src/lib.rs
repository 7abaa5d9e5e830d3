//! The Phantom client: join a heist as the blind player and play by touch and sound alone.
//!
//! The tree: [`device`] (which device, the steerable simulated hand), [`haptics`] (what a copy is to
//! the hand: its sphere tree and material), [`bench`] (the copy on the workbench, on `bevy_haptics`), [`explore`] (the touch bot), [`touch_bench`] (where it feels a copy: the running loop or the same loop in
//! lockstep), [`audio`] (kira, binaural voices,
//! synthesized sounds), [`speech`] (espeak-ng), [`status`] (the sentences), [`client`] (the Bevy app that
//! ties them to the session), [`cli`] (the command line) and, with the `spectator` feature, [`spectator`]
//! (a window for sighted onlookers).
#![warn(missing_docs)]

pub mod assemble;
pub mod bench;
pub mod cli;
pub mod client;
pub mod commands;
pub mod device;
pub mod error;
pub mod explore;
pub mod haptics;
pub mod host;
pub mod input;
pub mod practice;
pub mod prompt;
pub mod schedule;
pub mod settings;
pub mod sound;
#[cfg(feature = "spectator")]
pub mod spectator;
pub mod speech;
pub mod state;
pub mod status;
pub mod terminal;
pub mod touch_bench;
pub mod walkie;

pub use client::{PhantomClientPlugin, PhantomSettings, Workbench, start};
pub use error::ClientError;
/// The sounds (the shared `heist_audio` crate).
pub use heist_audio as audio;
