//! The connection as the player should hear of it ([`Link`]), and leaving it on purpose ([`Leaving`]).

use bevy::prelude::*;

use crate::inbox::Inbox;

/// Seconds of silence from the server after which the connection counts as lost (netcode sends a
/// keep-alive several times a second when there is nothing else to send).
pub const SILENCE_LOST_S: f64 = 3.0;

/// The connection to the server, as the player should hear of it.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Link {
    /// Nothing heard from the server yet.
    #[default]
    Connecting,
    /// The server was heard within [`SILENCE_LOST_S`].
    Up,
    /// Silent for [`SILENCE_LOST_S`] or more: the connection may come back until netcode gives up.
    Silent,
    /// The transport stopped: the server let us go, or went silent until netcode's timeout (6 s).
    Gone,
}

/// Leaving on purpose: set [`Leaving::since`] (or call [`Leaving::start`]) and the client says `Leave` to
/// the server (so the partner hears "left", not "dropped"), waits for the server to close the connection
/// (at most [`LEAVE_WAIT_S`]) and exits the app.
#[derive(Resource, Default, Debug)]
pub struct Leaving {
    /// When the player asked to leave (app time, seconds); `None` while staying.
    pub since: Option<f64>,
    sent: bool,
}

/// Seconds a leaving client waits for the server to let it go before exiting anyway.
pub const LEAVE_WAIT_S: f64 = 1.0;

impl Leaving {
    /// Starts leaving now (`now`: the app's real time, seconds).
    pub fn start(&mut self, now: f64) {
        self.since.get_or_insert(now);
    }
}

pub(crate) fn leave(
    mut leaving: ResMut<Leaving>,
    inbox: Res<Inbox>,
    time: Res<Time<Real>>,
    mut out: MessageWriter<heist_shared::protocol::ClientMsg>,
    mut exit: MessageWriter<AppExit>,
) {
    let Some(since) = leaving.since else { return };
    if !leaving.sent {
        leaving.sent = true;
        out.write(heist_shared::protocol::ClientMsg::Lobby(heist_shared::protocol::LobbyMsg::Leave));
    }
    if inbox.disconnect.is_some() || time.elapsed_secs_f64() - since > LEAVE_WAIT_S {
        exit.write(AppExit::Success);
    }
}
