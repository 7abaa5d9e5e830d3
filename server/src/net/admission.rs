//! Admitting a client: read role, session and seat ticket from its token, find its session, refuse
//! thieves of a taken or kept seat, and keep a dropped player's seat for them.

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use bevy_replicon::shared::backend::connected_client::NetworkId;
use std::time::Instant;

use heist_shared::protocol::{ClientRole, DisconnectReason, Role, SeatTicket, ServerMsg, TokenUserData};

use super::limits::MessageLimits;
use super::seats::Seat;
use super::settings::{Auth, NetSettings};
use super::transport::GameTransport;
use crate::session::{HostSession, Session, SessionTag};

/// An admitted player's client entity.
#[derive(Component, Clone, Copy, Debug)]
pub struct Player {
    /// Its session's entity.
    pub session: Entity,
    /// Role from the token.
    pub role: Role,
    /// Refused messages, leaking away at one per second: sustained abuse fills it.
    pub strikes: f32,
    /// Set once the client is being disconnected for abuse.
    pub expelled: bool,
    /// Set once the player said it is leaving (a clean quit, not a lost connection).
    pub leaving: bool,
    /// How much of each message kind it may still send.
    pub limits: MessageLimits,
    /// Where it connects from (for the log).
    pub peer: Option<std::net::SocketAddr>,
}

/// Disconnects `client` after telling it why.
pub fn refuse_and_disconnect(
    client: Entity,
    reason: DisconnectReason,
    messages: &mut MessageWriter<'_, ToClients<ServerMsg>>,
    disconnects: &mut MessageWriter<'_, DisconnectRequest>,
) {
    messages.write(ToClients {
        targets: SendTargets::Single(ClientId::Client(client)),
        message: ServerMsg::Disconnecting(reason),
    });
    disconnects.write(DisconnectRequest { client });
}

#[allow(clippy::too_many_arguments)]
pub(super) fn admit(
    add: On<Add, ConnectedClient>,
    mut commands: Commands,
    ids: Query<&NetworkId>,
    mut players: Query<&mut Player>,
    mut sessions: Query<(Entity, &mut Session)>,
    host: Res<HostSession>,
    transport: Option<Res<GameTransport>>,
    settings: Res<NetSettings>,
    mut messages: MessageWriter<ToClients<ServerMsg>>,
    mut disconnects: MessageWriter<DisconnectRequest>,
    time: Res<Time<Real>>,
) {
    let client = add.entity;
    let network_id = ids.get(client).ok().map(|id| id.get());
    let user_data = network_id.zip(transport.as_ref()).and_then(|(id, t)| t.user_data(id));
    let peer_addr = network_id.zip(transport.as_ref()).and_then(|(id, t)| t.client_addr(id));
    let peer = peer_addr.map_or_else(|| "an unknown address".to_owned(), |a| a.to_string());
    let claim = user_data.as_ref().and_then(TokenUserData::decode);
    // Secure: the token's session (the endpoint minted it, for an open session). Insecure (LAN
    // development, one session): the host's, whatever the claim says.
    let found = match (&settings.auth, &claim) {
        (Auth::Secure { .. }, Some(c)) => sessions.iter_mut().find(|(_, s)| s.id == c.session && s.closed_at.is_none()),
        (Auth::Insecure, Some(_)) => host.0.and_then(|h| sessions.get_mut(h).ok()),
        _ => None,
    };
    let (Some(claim), Some((session_entity, mut session))) = (claim, found) else {
        warn!("refused the connection from {peer}: its token is foreign, missing or for a session that is over");
        refuse_and_disconnect(client, DisconnectReason::BadToken, &mut messages, &mut disconnects);
        return;
    };
    let session = &mut *session;
    let role = claim.role;
    let (ticket, resumed) = match (claim.ticket, session.seats.get(role)) {
        (None, Seat::Free) => (SeatTicket::random(), false),
        (Some(t), Seat::Taken(ticket) | Seat::Kept { ticket, .. }) if t == ticket => (ticket, true),
        (claimed, seat) => {
            let reason = match (claimed, seat) {
                (None, Seat::Taken(_)) => DisconnectReason::RoleTaken(role),
                (None, _) => DisconnectReason::SeatHeld(role),
                (Some(_), _) => DisconnectReason::BadSeat,
            };
            warn!("refused the connection from {peer} as {role}: {reason:?}");
            session.log.line(session.game.elapsed_s, format!("a {role} was refused: {reason:?}"));
            refuse_and_disconnect(client, reason, &mut messages, &mut disconnects);
            return;
        }
    };
    // A restarted client may come back before its old connection timed out: the new one replaces it.
    if let Some(old) = session.roles.get(role) {
        if let Ok(mut player) = players.get_mut(old) {
            player.expelled = true; // nothing more it says counts
        }
        info!("{role} came back on a new connection: closing the old one");
        refuse_and_disconnect(old, DisconnectReason::Replaced, &mut messages, &mut disconnects);
    }
    *session.roles.slot(role) = Some(client);
    session.seats.set(role, Seat::Taken(ticket));
    let limits = MessageLimits::new(time.elapsed_secs_f64());
    commands.entity(client).insert((
        Player {
            session: session_entity,
            role,
            strikes: 0.0,
            expelled: false,
            leaving: false,
            limits,
            peer: peer_addr,
        },
        ClientRole(role),
        SessionTag(session.id),
    ));
    messages.write(ToClients {
        targets: SendTargets::Single(ClientId::Client(client)),
        message: ServerMsg::Welcome { role, level: Box::new(session.game.level.clone()), seat: ticket, resumed },
    });
    if resumed {
        settings.metrics.resumes.inc();
        info!("{role} took the seat back from {peer}");
        session.game.resume(role);
    } else {
        info!("{role} joined from {peer}");
        session.game.join(role);
    }
}

/// A connection ended: a player who left on purpose (or was expelled) frees the seat; one whose connection
/// was lost (fell silent) has it kept for them ([`Seat::Kept`]) while the game keeps it.
pub(super) fn forget(
    remove: On<Remove, ConnectedClient>,
    players: Query<&Player>,
    ids: Query<&NetworkId>,
    transport: Option<Res<GameTransport>>,
    mut sessions: Query<&mut Session>,
) {
    let Ok(player) = players.get(remove.entity) else { return };
    let Ok(mut session) = sessions.get_mut(player.session) else { return };
    let session = &mut *session;
    if session.roles.get(player.role) != Some(remove.entity) {
        return; // refused, or replaced by its own player's new connection
    }
    *session.roles.slot(player.role) = None;
    // Closing the connection on purpose (a `Leave`, or netcode's goodbye when a client quits without one)
    // is leaving, and an expelled client keeps nothing; only a connection that fell silent is a drop,
    // whose seat is kept.
    let departed = ids.get(remove.entity).ok().zip(transport.as_ref()).and_then(|(id, t)| t.departure(id.get()));
    let dropped = !player.leaving && !player.expelled && departed.is_none();
    session.game.leave(player.role, dropped);
    let seat = match session.seats.get(player.role) {
        Seat::Taken(ticket) if session.game.is_seat_kept(player.role) => Seat::Kept { ticket, since: Instant::now() },
        _ => Seat::Free,
    };
    session.seats.set(player.role, seat);
}

/// Frees a kept seat once the game gave it up (its player did not come back in time).
pub(super) fn give_up_seats(sessions: Query<&Session>) {
    for session in &sessions {
        for role in [Role::Vive, Role::Phantom] {
            let kept = matches!(session.seats.get(role), Seat::Kept { .. });
            if kept && session.roles.get(role).is_none() && !session.game.is_seat_kept(role) {
                session.seats.set(role, Seat::Free);
            }
        }
    }
}
