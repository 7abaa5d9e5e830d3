//! The server's network side: the UDP transport, the token endpoint, admitting clients by the role in
//! their token, and moving messages between clients and the game.
//!
//! Systems run in `PreUpdate` (receive, after replicon's receive) and `PostUpdate` (send, before
//! replicon's send).

mod admission;
pub mod codes;
pub mod limits;
pub mod receive;
pub mod registry;
pub mod seats;
pub mod send;
mod settings;
pub mod tokens;
pub mod transport;
pub mod voice;

use std::net::{SocketAddr, UdpSocket};
use std::time::{SystemTime, UNIX_EPOCH};

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use bevy_replicon_renet::renet::ServerEvent;
use bevy_replicon_renet::{RenetServer, RenetServerEvent};
use heist_shared::protocol::{PROTOCOL_ID, Role};
use heist_transport::IntakeLimits;
use heist_transport::renetcode::{ServerAuthentication, ServerConfig};

pub use admission::Player;
pub use seats::Roles;
pub use settings::{Auth, NetSettings, NewSessions};

use crate::session::{HostSession, Session};

/// The bound game socket, waiting for the transport to be created at start-up.
#[derive(Resource)]
struct PendingSocket(Option<UdpSocket>, IntakeLimits);

/// The server's public game address.
#[derive(Resource, Clone, Copy, Debug)]
pub struct ServerAddr(pub SocketAddr);

/// The network schedule sets, in order.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum NetSystems {
    /// `PreUpdate`, after replicon's receive: client messages into the game.
    Receive,
    /// `PostUpdate`, before replicon's send: game output to clients.
    Send,
}

/// Adds the server transport and message handling.
pub struct ServerNetPlugin {
    /// Bound UDP socket for the game.
    pub socket: std::sync::Mutex<Option<UdpSocket>>,
    /// Settings.
    pub settings: NetSettings,
    /// The game socket's limits.
    pub intake: IntakeLimits,
}

impl Plugin for ServerNetPlugin {
    fn build(&self, app: &mut App) {
        let socket = self.socket.lock().ok().and_then(|mut s| s.take());
        if let Some(addr) = socket.as_ref().and_then(|s| s.local_addr().ok()) {
            app.insert_resource(ServerAddr(addr));
        }
        app.insert_resource(PendingSocket(socket, self.intake))
            .insert_resource(self.settings.clone())
            .add_systems(Startup, start_transport)
            .add_systems(First, open_sessions)
            .add_observer(admission::admit)
            .add_observer(admission::forget)
            .add_observer(log_disconnect)
            .configure_sets(PreUpdate, NetSystems::Receive.after(ServerSystems::Receive))
            .configure_sets(PostUpdate, NetSystems::Send.before(ServerSystems::Send))
            // The sessions' mirrors are up to date before what is sent.
            .configure_sets(PostUpdate, crate::session::SessionSystems::Mirror.before(NetSystems::Send))
            .add_systems(
                PreUpdate,
                (receive::apply_client_messages, voice::relay_voice).chain().in_set(NetSystems::Receive),
            )
            .add_systems(
                PostUpdate,
                (send::send_outgoing, admission::give_up_seats, close_sessions).chain().in_set(NetSystems::Send),
            );
        transport::add_systems(app);
    }
}

fn start_transport(
    mut commands: Commands,
    mut pending: ResMut<PendingSocket>,
    settings: Res<NetSettings>,
    channels: Res<RepliconChannels>,
) {
    let Some(socket) = pending.0.take() else {
        error!("no game socket to serve on");
        return;
    };
    let Ok(addr) = socket.local_addr() else {
        error!("the game socket has no local address");
        return;
    };
    let authentication = match &settings.auth {
        Auth::Secure { private_key, .. } => ServerAuthentication::Secure { private_key: *private_key },
        Auth::Insecure => ServerAuthentication::Unsecure,
    };
    let config = ServerConfig {
        current_time: SystemTime::now().duration_since(UNIX_EPOCH).unwrap_or_default(),
        // This shard's sessions' players, each twice (a player who dropped comes back on a new connection
        // while the old one times out), and 16 more (clients told why they are refused). Not the whole
        // server's: netcode keeps a slot of 2 kB a client and walks every slot each tick to list its
        // clients, so slots sized for the server made every shard's tick O(sessions).
        max_clients: shard_slots(settings.registry.shard_size()),
        protocol_id: PROTOCOL_ID,
        public_addresses: vec![settings.advertise.unwrap_or(addr)],
        authentication,
    };
    match transport::GameTransport::new(socket, config, pending.1) {
        Ok(transport) => {
            commands.insert_resource(RenetServer::new(heist_client::connection_config(&channels)));
            commands.insert_resource(transport);
        }
        Err(e) => error!("cannot start the game transport on {addr}: {e}"),
    }
}

/// The netcode slots of a shard playing at most `shard_size` sessions.
pub fn shard_slots(shard_size: usize) -> usize {
    (shard_size * 4 + 16).min(MAX_CLIENTS)
}

/// Netcode's most clients on one server.
pub const MAX_CLIENTS: usize = 1024;
/// The most sessions one server may host (two players each, within [`MAX_CLIENTS`]).
pub const MAX_SESSIONS: usize = 500;

/// Spawns the game of every session the token endpoint opened.
fn open_sessions(mut commands: Commands, settings: Res<NetSettings>) {
    for entry in settings.registry.take_opened(settings.shard) {
        let mut session = settings.new_sessions.session(&entry, None);
        session.log.record(0.0, crate::session::Record::SessionCreated, "session created; waiting for players".into());
        crate::session::spawn_session(&mut commands, session);
    }
}

/// Seconds between telling the players a session is over and freeing it (so the message goes).
const CLOSE_LINGER_S: f64 = 1.0;

/// Once a game is closed (idle after a result, or deserted): closes its session in the registry (its code
/// and seats stop working), tells each player why and lets them go, and a second later despawns it with
/// its mirrors. The end of the host's session (there is one unless `serve`d) ends the app instead (`host`
/// then exits 0); a `serve`d server runs on.
#[allow(clippy::too_many_arguments)]
fn close_sessions(
    mut commands: Commands,
    mut sessions: Query<(Entity, &mut Session)>,
    settings: Res<NetSettings>,
    host: Res<HostSession>,
    mut messages: MessageWriter<ToClients<heist_shared::protocol::ServerMsg>>,
    mut disconnects: MessageWriter<DisconnectRequest>,
    mut exit: MessageWriter<AppExit>,
    time: Res<Time<Real>>,
) {
    let now = time.elapsed_secs_f64();
    for (entity, mut session) in &mut sessions {
        if !session.game.closed {
            continue;
        }
        match session.closed_at {
            None => {
                session.closed_at = Some(now);
                let why = if session.game.draining {
                    "the server is shutting down"
                } else if session.game.present == (false, false) {
                    "nobody is left in it"
                } else {
                    "nobody asked for another round"
                };
                info!("session {} is over: {why}", session.log.id);
                settings.registry.close(session.id);
                let t = session.game.elapsed_s;
                session.log.record(t, crate::session::Record::SessionEnded, format!("session ended: {why}"));
                let reason = if session.game.draining {
                    heist_shared::protocol::DisconnectReason::ServerShutdown
                } else {
                    heist_shared::protocol::DisconnectReason::SessionEnded
                };
                for client in [session.roles.vive, session.roles.phantom].into_iter().flatten() {
                    admission::refuse_and_disconnect(client, reason.clone(), &mut messages, &mut disconnects);
                }
            }
            Some(at) if now - at >= CLOSE_LINGER_S => {
                if host.0 == Some(entity) {
                    exit.write(AppExit::Success);
                } else {
                    commands.entity(entity).despawn();
                }
            }
            Some(_) => {}
        }
    }
}

/// Says why renet let a client go (a channel overflow, a malformed packet, a timeout).
fn log_disconnect(event: On<RenetServerEvent>) {
    if let ServerEvent::ClientDisconnected { client_id, reason } = &**event {
        info!("client {client_id} disconnected: {reason}");
    }
}

/// Bytes the kernel may queue for the game socket between two reads: a tick's datagrams from every
/// client of every session (at 500 sessions, about 2,000 datagrams, connection requests 1,078 bytes each).
/// The kernel caps it at `net.core.rmem_max`.
pub const GAME_SOCKET_BUFFER: usize = 4 << 20;

/// Binds the game socket (loopback for tests, any address for hosting), with room for a tick's worth of
/// datagrams from every client ([`GAME_SOCKET_BUFFER`]; the default, ~200 KB, holds ~190 connection
/// requests: the rest are dropped before the server reads them).
pub fn bind_game_socket(addr: SocketAddr) -> std::io::Result<UdpSocket> {
    use socket2::{Domain, Protocol, Socket, Type};
    let socket = Socket::new(Domain::for_address(addr), Type::DGRAM, Some(Protocol::UDP))?;
    if let Err(e) = socket.set_recv_buffer_size(GAME_SOCKET_BUFFER) {
        warn!("cannot enlarge the game socket's receive buffer: {e}");
    }
    socket.bind(&addr.into())?;
    Ok(socket.into())
}

/// The address to tell players when the server listens on every interface (`bound` is unspecified, like
/// 0.0.0.0): the interface address of the default route, or an error saying to pass `--advertise`. Tokens
/// carrying 0.0.0.0 would send remote players nowhere.
pub fn advertise_for(bound: SocketAddr) -> anyhow::Result<SocketAddr> {
    match route_address(bound) {
        Some(ip) => {
            let addr = SocketAddr::new(ip, bound.port());
            info!(
                "listening on {bound}: advertising {addr} to players (the default route's interface; --advertise sets another)"
            );
            Ok(addr)
        }
        None => anyhow::bail!(
            "--bind {bound} listens on every interface, but no interface with a route was found to tell players about: \
             pass --advertise ADDR (the address players reach)"
        ),
    }
}

/// The local address the system would send from towards the internet (no packet is sent: connecting a
/// UDP socket only chooses a route). `None` without a route, or when it is only loopback.
fn route_address(bound: SocketAddr) -> Option<std::net::IpAddr> {
    let (local, probe) = if bound.is_ipv4() { ("0.0.0.0:0", "192.0.2.1:9") } else { ("[::]:0", "[2001:db8::1]:9") };
    let socket = UdpSocket::bind(local).ok()?;
    socket.connect(probe).ok()?;
    let ip = socket.local_addr().ok()?.ip();
    (!ip.is_unspecified() && !ip.is_loopback()).then_some(ip)
}

/// How many clients are admitted as players, in every session.
pub fn admission_count(world: &mut World) -> usize {
    world.query::<&Player>().iter(world).count()
}

/// The role a connected client entity plays, if admitted.
pub fn role_of(players: &Query<'_, '_, &Player>, client: Entity) -> Option<Role> {
    players.get(client).ok().map(|p| p.role)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_game_socket_has_room_for_a_tick_of_every_clients_datagrams() {
        let socket = bind_game_socket("127.0.0.1:0".parse().unwrap()).unwrap();
        let size = socket2::SockRef::from(&socket).recv_buffer_size().unwrap();
        // The kernel caps the request at net.core.rmem_max (and reports twice what it grants).
        let cap = std::fs::read_to_string("/proc/sys/net/core/rmem_max")
            .ok()
            .and_then(|s| s.trim().parse::<usize>().ok())
            .unwrap_or(GAME_SOCKET_BUFFER);
        assert!(size >= GAME_SOCKET_BUFFER.min(cap), "{size} bytes (rmem_max {cap})");
    }
}
