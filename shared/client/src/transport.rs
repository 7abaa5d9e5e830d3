//! The client's socket: datagrams from the server through heist_transport's checks into netcode and
//! renet, renet's packets back out. Stands where bevy_renet's `NetcodeClientTransport` would (same
//! schedule slots), so a datagram spoofed from the server's address cannot panic the client.

use std::net::{SocketAddr, UdpSocket};
use std::time::{SystemTime, UNIX_EPOCH};

use bevy::prelude::*;
use bevy_replicon::prelude::RepliconChannels;
use bevy_replicon_renet::renet::ConnectionConfig;
use bevy_replicon_renet::{RenetChannelsExt, RenetClient, RenetClientPlugin, RenetReceive, RenetSend};
use heist_transport::renetcode::{ClientAuthentication, ConnectToken, DisconnectReason, NetcodeError};
use heist_transport::socket::{self, send_to};
use heist_transport::{ClientIntake, TransportError};

use crate::JoinError;

/// Datagrams read per frame at most, so a flood cannot stall a frame.
pub const MAX_DATAGRAMS_PER_FRAME: usize = 1024;

/// The client's socket and the intake that checks what arrives on it.
#[derive(Resource)]
pub struct ClientTransport {
    socket: UdpSocket,
    intake: ClientIntake,
    buffer: Box<[u8; socket::BUFFER_BYTES]>,
    /// Why the transport stopped, once it has.
    pub stopped: Option<String>,
    /// When the server was last heard (a datagram from it that passed the checks), app real time.
    pub heard_at: Option<std::time::Duration>,
}

impl ClientTransport {
    /// Serves `socket` (made non-blocking) for `intake`.
    pub fn new(socket: UdpSocket, intake: ClientIntake) -> std::io::Result<Self> {
        socket.set_nonblocking(true)?;
        Ok(Self { socket, intake, buffer: Box::new([0; socket::BUFFER_BYTES]), stopped: None, heard_at: None })
    }

    /// Why netcode gave up, if it did.
    pub fn disconnect_reason(&self) -> Option<DisconnectReason> {
        self.intake.disconnect_reason()
    }

    /// The server's address.
    pub fn server_addr(&self) -> SocketAddr {
        self.intake.server_addr()
    }

    /// Datagrams and payloads refused so far.
    pub fn refused(&self) -> u64 {
        self.intake.refused()
    }
}

/// Adds the transport's systems (the resource is inserted by `connect`).
pub(crate) fn add_systems(app: &mut App) {
    app.add_systems(
        PreUpdate,
        receive
            .in_set(RenetReceive)
            .after(RenetClientPlugin::update_system)
            .run_if(resource_exists::<ClientTransport>)
            .run_if(resource_exists::<RenetClient>),
    )
    .add_systems(
        PostUpdate,
        send.in_set(RenetSend).run_if(resource_exists::<ClientTransport>).run_if(resource_exists::<RenetClient>),
    )
    .add_systems(
        Last,
        disconnect_on_exit.run_if(resource_exists::<ClientTransport>).run_if(resource_exists::<RenetClient>),
    );
}

fn stop(stopped: &mut Option<String>, error: TransportError) {
    if stopped.is_none() {
        // Said once: the transport keeps reporting the same reason every frame.
        match &error {
            TransportError::Netcode(NetcodeError::Disconnected(reason)) => info!("disconnected: {reason}"),
            e => warn!("connection lost: {e}"),
        }
        *stopped = Some(error.to_string());
    }
}

fn receive(mut transport: ResMut<ClientTransport>, mut renet: ResMut<RenetClient>, time: Res<Time<Real>>) {
    let ClientTransport { socket, intake, buffer, stopped, heard_at } = &mut *transport;
    let mut send = send_to(socket);
    if let Err(e) = intake.begin_update(&mut renet, &mut send) {
        stop(stopped, e);
        return;
    }
    let now = time.elapsed();
    let drained = socket::drain(socket, buffer, MAX_DATAGRAMS_PER_FRAME, |from, datagram| {
        match intake.receive(from, datagram, &mut renet) {
            Ok(()) => *heard_at = Some(now),
            Err(r) => debug!("refused a datagram from {from}: {r}"),
        }
    });
    if let Err(e) = drained {
        stop(stopped, TransportError::Io(e));
    }
    intake.finish_update(time.delta(), &mut send);
}

fn send(mut transport: ResMut<ClientTransport>, mut renet: ResMut<RenetClient>) {
    let ClientTransport { socket, intake, stopped, .. } = &mut *transport;
    if let Err(e) = intake.send_packets(&mut renet, &mut send_to(socket)) {
        stop(stopped, e);
    }
}

fn disconnect_on_exit(exit: MessageReader<AppExit>, mut transport: ResMut<ClientTransport>) {
    if !exit.is_empty() {
        let ClientTransport { socket, intake, .. } = &mut *transport;
        intake.disconnect(&mut send_to(socket));
    }
}

/// A fresh renet client and transport for `token` (the server is the first address it names).
pub(crate) fn open_with_token(
    token: ConnectToken,
    channels: &RepliconChannels,
) -> Result<(RenetClient, ClientTransport), JoinError> {
    let server = token.server_addresses.iter().flatten().next().copied().ok_or(JoinError::NoServerAddress)?;
    open(server, ClientAuthentication::Secure { connect_token: token }, channels)
}

/// A renet client and transport authenticating with `auth` to `server`.
pub(crate) fn open(
    server: SocketAddr,
    auth: ClientAuthentication,
    channels: &RepliconChannels,
) -> Result<(RenetClient, ClientTransport), JoinError> {
    let bind = if server.ip().is_loopback() { "127.0.0.1:0" } else { "0.0.0.0:0" };
    let socket = UdpSocket::bind(bind).map_err(JoinError::Socket)?;
    let now = SystemTime::now().duration_since(UNIX_EPOCH).unwrap_or_default();
    let intake = ClientIntake::new(now, auth).map_err(|e| JoinError::Transport(e.to_string()))?;
    let transport = ClientTransport::new(socket, intake).map_err(JoinError::Socket)?;
    Ok((RenetClient::new(connection_config(channels)), transport))
}

/// renet's channels for the registered protocol: the same on the server and every client (call after all
/// protocol registration).
pub fn connection_config(channels: &RepliconChannels) -> ConnectionConfig {
    ConnectionConfig {
        server_channels_config: channels.server_configs(),
        client_channels_config: channels.client_configs(),
        ..Default::default()
    }
}
