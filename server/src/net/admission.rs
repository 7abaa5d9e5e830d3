//! Admitting a client: read role and session from its token, refuse thieves of a taken role.

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use bevy_replicon::shared::backend::connected_client::NetworkId;
use heist_shared::protocol::{ClientRole, DisconnectReason, Role, ServerMsg, TokenUserData};

use super::limits::MessageLimits;
use super::transport::GameTransport;
use super::{Auth, NetSettings};
use crate::session::{GameState, SessionLog};

/// An admitted player's client entity.
#[derive(Component, Clone, Copy, Debug)]
pub struct Player {
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

/// Which client entity plays which role.
#[derive(Resource, Default, Debug)]
pub struct Roles {
    /// Vive's client.
    pub vive: Option<Entity>,
    /// Phantom's client.
    pub phantom: Option<Entity>,
}

impl Roles {
    /// The client playing `role`.
    pub fn get(&self, role: Role) -> Option<Entity> {
        match role {
            Role::Vive => self.vive,
            Role::Phantom => self.phantom,
        }
    }

    fn slot(&mut self, role: Role) -> &mut Option<Entity> {
        match role {
            Role::Vive => &mut self.vive,
            Role::Phantom => &mut self.phantom,
        }
    }
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
    transport: Option<Res<GameTransport>>,
    settings: Res<NetSettings>,
    mut roles: ResMut<Roles>,
    mut game: ResMut<GameState>,
    mut log: ResMut<SessionLog>,
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
    let claim = match (&settings.auth, claim) {
        (Auth::Secure { session, .. }, Some(c)) if c.session == *session => c,
        (Auth::Insecure, Some(c)) => c,
        _ => {
            warn!("refused the connection from {peer}: its token is foreign or missing");
            log.line(game.0.elapsed_s, "a client with a foreign or missing token was refused".into());
            refuse_and_disconnect(client, DisconnectReason::BadToken, &mut messages, &mut disconnects);
            return;
        }
    };
    let role = claim.role;
    if roles.get(role).is_some() {
        warn!("refused the connection from {peer}: the {role} role is taken");
        log.line(game.0.elapsed_s, format!("a second {role} was refused: the role is taken"));
        refuse_and_disconnect(client, DisconnectReason::RoleTaken(role), &mut messages, &mut disconnects);
        return;
    }
    *roles.slot(role) = Some(client);
    settings.roles.set(role, true);
    let limits = MessageLimits::new(time.elapsed_secs_f64());
    commands.entity(client).insert((
        Player { role, strikes: 0.0, expelled: false, leaving: false, limits, peer: peer_addr },
        ClientRole(role),
    ));
    game.0.join(role);
    info!("{role} joined from {peer}");
    messages.write(ToClients {
        targets: SendTargets::Single(ClientId::Client(client)),
        message: ServerMsg::Welcome { role, level: Box::new(game.0.level.clone()) },
    });
}

pub(super) fn forget(
    remove: On<Remove, ConnectedClient>,
    players: Query<&Player>,
    settings: Res<NetSettings>,
    mut roles: ResMut<Roles>,
    mut game: ResMut<GameState>,
) {
    let Ok(player) = players.get(remove.entity) else { return };
    if roles.get(player.role) == Some(remove.entity) {
        *roles.slot(player.role) = None;
        settings.roles.set(player.role, false);
        game.0.leave(player.role, !player.leaving);
    }
}
