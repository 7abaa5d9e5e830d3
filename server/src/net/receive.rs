//! Client messages into the game: decode (already done by the protocol), check the rate, apply or refuse.

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use heist_shared::protocol::{ClientMsg, DisconnectReason, LobbyMsg, ServerMsg};

use super::NetSettings;
use super::admission::{Player, refuse_and_disconnect};
use crate::session::Session;

/// Applies every message received this frame, in order.
#[allow(clippy::too_many_arguments)]
pub fn apply_client_messages(
    mut received: MessageReader<FromClient<ClientMsg>>,
    mut players: Query<&mut Player>,
    mut sessions: Query<&mut Session>,
    settings: Res<NetSettings>,
    time: Res<Time<Real>>,
    mut messages: MessageWriter<ToClients<ServerMsg>>,
    mut disconnects: MessageWriter<DisconnectRequest>,
) {
    let leak = time.delta_secs();
    for mut player in &mut players {
        player.strikes = (player.strikes - leak).max(0.0);
    }
    for FromClient { client_id, message } in received.read() {
        let ClientId::Client(client) = *client_id else { continue };
        let Ok(mut player) = players.get_mut(client) else {
            // Not admitted (yet, or refused): nothing it says counts.
            continue;
        };
        if player.expelled {
            continue; // being disconnected: nothing more it says counts
        }
        let Ok(mut session) = sessions.get_mut(player.session) else { continue };
        let Session { game, log, .. } = &mut *session;
        let now = time.elapsed_secs_f64();
        let applied = player.limits.check(message, now).and_then(|()| game.apply(player.role, message));
        if applied.is_ok() && *message == ClientMsg::Lobby(LobbyMsg::Leave) {
            player.leaving = true;
            disconnects.write(DisconnectRequest { client });
        }
        if let Err(refusal) = applied {
            player.strikes += 1.0;
            let peer = player.peer.map_or_else(|| "?".to_owned(), |p| p.to_string());
            info!("refused a {} message from {peer}: {refusal:?}", player.role);
            log.debug(game.elapsed_s, format!("{} refused: {refusal:?}", player.role));
            messages.write(ToClients {
                targets: SendTargets::Single(ClientId::Client(client)),
                message: ServerMsg::Refused(refusal),
            });
            if player.strikes > settings.abuse_limit as f32 {
                player.expelled = true;
                warn!("disconnecting {} at {peer} for abuse", player.role);
                log.line(game.elapsed_s, format!("{} disconnected for abuse", player.role));
                refuse_and_disconnect(client, DisconnectReason::Abuse, &mut messages, &mut disconnects);
            }
        }
    }
}
