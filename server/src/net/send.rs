//! Game output to clients: each message goes to both players or to one role only.

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use heist_shared::protocol::ServerMsg;

use crate::game::Outgoing;
use crate::session::Session;

/// Sends what each game produced this frame to its players and writes it to its session log.
pub fn send_outgoing(mut sessions: Query<&mut Session>, mut messages: MessageWriter<ToClients<ServerMsg>>) {
    for mut session in &mut sessions {
        let Session { game, log, roles, .. } = &mut *session;
        let elapsed = game.elapsed_s;
        let outgoing: Vec<Outgoing> = game.drain_outgoing().collect();
        for out in outgoing {
            let (targets, msg) = match out {
                Outgoing::All(msg) => ([roles.vive, roles.phantom], msg),
                Outgoing::To(role, msg) => ([roles.get(role), None], msg),
            };
            if let ServerMsg::Event(event) = &msg {
                log.event(elapsed, game, event);
            }
            for client in targets.into_iter().flatten() {
                messages
                    .write(ToClients { targets: SendTargets::Single(ClientId::Client(client)), message: msg.clone() });
            }
        }
    }
}
