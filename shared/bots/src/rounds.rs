//! Rematches: after a result each bot asks for another round until [`Rounds`] have been played.

use bevy::prelude::*;
use heist_client::Inbox;
use heist_shared::protocol::{ClientMsg, LobbyMsg, Phase, SessionView};

/// How many rounds the bots play in one session: after each result they ask for another round until this
/// many were played. Without it (or with 1) they play one.
#[derive(Resource, Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rounds(pub u32);

/// Asks once per result while rounds remain.
pub(crate) fn ask_for_another_round(
    rounds: Option<Res<Rounds>>,
    inbox: Res<Inbox>,
    session: Query<&SessionView>,
    mut asked_after: Local<u32>,
    mut out: MessageWriter<ClientMsg>,
) {
    let Some(rounds) = rounds else { return };
    let Ok(session) = session.single() else { return };
    let round = inbox.current_round();
    if matches!(session.phase, Phase::Won | Phase::Lost(_)) && round < rounds.0 && *asked_after < round {
        *asked_after = round;
        out.write(ClientMsg::Lobby(LobbyMsg::Rematch));
    }
}
