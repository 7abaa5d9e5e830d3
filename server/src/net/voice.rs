//! The walkie-talkie relay: a voice frame goes to the sender's partner in the sender's session and to
//! nobody else, within the sender's voice rate ([`super::limits::VOICE`]); the server never decodes it.

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use heist_shared::protocol::{ClientVoice, DisconnectReason, PartnerVoice, ServerMsg};

use super::admission::{Player, refuse_and_disconnect};
use super::limits::VOICE_STRIKE;
use super::settings::NetSettings;
use crate::session::Session;

/// Relays every voice frame received this frame; a malformed one counts as a refusal, one over the rate
/// as a tenth of one (neither is answered: a voice frame is never worth a message back); past the abuse
/// limit the sender is disconnected, as for any other kind of message.
#[allow(clippy::too_many_arguments)]
pub fn relay_voice(
    mut received: MessageReader<FromClient<ClientVoice>>,
    mut players: Query<&mut Player>,
    sessions: Query<&Session>,
    settings: Res<NetSettings>,
    time: Res<Time<Real>>,
    mut out: MessageWriter<ToClients<PartnerVoice>>,
    mut messages: MessageWriter<ToClients<ServerMsg>>,
    mut disconnects: MessageWriter<DisconnectRequest>,
) {
    let now = time.elapsed_secs_f64();
    for FromClient { client_id, message } in received.read() {
        let ClientId::Client(client) = *client_id else { continue };
        let Ok(mut player) = players.get_mut(client) else { continue };
        if player.expelled {
            continue;
        }
        let refused = match message {
            ClientVoice::Malformed => Some(("malformed", 1.0)),
            ClientVoice::Frame(_) if !player.limits.check_voice(now) => Some(("rate_limited", VOICE_STRIKE)),
            ClientVoice::Frame(_) => None,
        };
        if let Some((kind, strike)) = refused {
            settings.metrics.refuse("voice", kind);
            player.strikes += strike;
            if player.strikes > settings.abuse_limit as f32 {
                player.expelled = true;
                warn!("disconnecting {} for a flood of voice frames", player.role);
                refuse_and_disconnect(client, DisconnectReason::Abuse, &mut messages, &mut disconnects);
            }
            continue;
        }
        let ClientVoice::Frame(frame) = message else { continue };
        let Some(to) = sessions.get(player.session).ok().and_then(|s| s.roles.get(player.role.partner())) else {
            continue;
        };
        out.write(ToClients {
            targets: SendTargets::Single(ClientId::Client(to)),
            message: PartnerVoice(frame.clone()),
        });
    }
}
