//! Game output to clients: each message goes to both players or to one role only.

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use heist_shared::protocol::ServerMsg;

use super::admission::Roles;
use crate::game::Outgoing;
use crate::session::{GameState, SessionLog};

/// Sends what the game produced this frame and writes it to the session log.
pub fn send_outgoing(
    mut game: ResMut<GameState>,
    roles: Res<Roles>,
    mut log: ResMut<SessionLog>,
    mut messages: MessageWriter<ToClients<ServerMsg>>,
) {
    let elapsed = game.0.elapsed_s;
    let outgoing: Vec<Outgoing> = game.0.drain_outgoing().collect();
    for out in outgoing {
        let (targets, msg) = match out {
            Outgoing::All(msg) => (vec![roles.vive, roles.phantom], msg),
            Outgoing::To(role, msg) => (vec![roles.get(role)], msg),
        };
        if let ServerMsg::Event(event) = &msg {
            log.event(elapsed, &game.0, event);
        }
        for client in targets.into_iter().flatten() {
            messages.write(ToClients { targets: SendTargets::Single(ClientId::Client(client)), message: msg.clone() });
        }
    }
}
