//! The order of the Phantom client's systems in a frame, which every part of the client (the session,
//! the settings menu, the walkie-talkie, the sounds) places its own systems in, and the server's events
//! as the `Receive` set hands them on.

use bevy::prelude::*;
use heist_shared::protocol::GameEvent;

/// System sets of the Phantom client, chained in `Update`.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum PhantomSystems {
    /// Server events and copies in; the haptic rig polled.
    Receive,
    /// Lobby, keys, verdicts, the bot.
    Play,
    /// Speech, museum sounds, contact sound, tool pose out.
    Sound,
}

/// A server event, re-sent as a Bevy message so every system can read it.
#[derive(Message, Clone, Debug, PartialEq)]
pub struct HeistEvent(pub GameEvent);
