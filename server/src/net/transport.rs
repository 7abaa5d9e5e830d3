//! The game socket: every datagram through heist_transport's checks into netcode and renet, and renet's
//! packets back out. Stands where bevy_renet's `NetcodeServerTransport` would (same schedule slots), so a
//! datagram that would panic renetcode or renet never reaches them.

use std::net::{SocketAddr, UdpSocket};

use bevy::prelude::*;
use bevy_replicon_renet::{RenetReceive, RenetSend, RenetServer, RenetServerPlugin};
use heist_transport::renetcode::{NETCODE_USER_DATA_BYTES, ServerConfig};
use heist_transport::socket::{self, send_to};
use heist_transport::{IntakeLimits, IntakeStats, ServerIntake};

/// Datagrams read per frame at most: a flood waits in the kernel's buffer (and is dropped there) instead
/// of stalling the tick.
pub const MAX_DATAGRAMS_PER_FRAME: usize = 4096;

/// The bound game socket and the intake that checks what arrives on it.
#[derive(Resource)]
pub struct GameTransport {
    socket: UdpSocket,
    intake: ServerIntake,
    buffer: Box<[u8; socket::BUFFER_BYTES]>,
    bytes: Traffic,
}

/// Bytes through the game socket so far (UDP payloads: everything netcode and renet add included).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Traffic {
    /// Received (every datagram read, refused ones included).
    pub received: u64,
    /// Sent.
    pub sent: u64,
    /// Datagrams received.
    pub datagrams_received: u64,
    /// Datagrams sent.
    pub datagrams_sent: u64,
}

/// `send_to` that also counts what it sends.
fn counted<'a>(socket: &'a UdpSocket, traffic: &'a mut Traffic) -> impl FnMut(SocketAddr, &[u8]) + 'a {
    let mut send = send_to(socket);
    move |to, bytes| {
        traffic.sent += bytes.len() as u64;
        traffic.datagrams_sent += 1;
        send(to, bytes);
    }
}

impl GameTransport {
    /// Serves `socket` (made non-blocking) with a netcode server made from `config`.
    pub fn new(socket: UdpSocket, config: ServerConfig, limits: IntakeLimits) -> std::io::Result<Self> {
        socket.set_nonblocking(true)?;
        Ok(Self {
            socket,
            intake: ServerIntake::new(config, limits),
            buffer: Box::new([0; socket::BUFFER_BYTES]),
            bytes: Traffic::default(),
        })
    }

    /// The user data in a connected client's token.
    pub fn user_data(&self, client_id: u64) -> Option<[u8; NETCODE_USER_DATA_BYTES]> {
        self.intake.user_data(client_id)
    }

    /// A connected client's address.
    pub fn client_addr(&self, client_id: u64) -> Option<SocketAddr> {
        self.intake.client_addr(client_id)
    }

    /// How a client that just went left, unless it fell silent (see [`ServerIntake::departure`]).
    pub fn departure(&self, client_id: u64) -> Option<heist_transport::Departure> {
        self.intake.departure(client_id)
    }

    /// Clients the netcode server holds a slot for.
    pub fn max_clients(&self) -> usize {
        self.intake.max_clients()
    }

    /// Bytes through the socket so far.
    pub fn traffic(&self) -> Traffic {
        self.bytes
    }

    /// What the intake passed and refused so far.
    pub fn stats(&self) -> IntakeStats {
        self.intake.stats()
    }
}

/// Adds the transport's systems; the resource is inserted at start-up by the network plugin.
pub(super) fn add_systems(app: &mut App) {
    app.add_systems(
        PreUpdate,
        receive
            .in_set(RenetReceive)
            .after(RenetServerPlugin::update_system)
            .before(RenetServerPlugin::emit_server_events_system)
            .run_if(resource_exists::<GameTransport>)
            .run_if(resource_exists::<RenetServer>),
    )
    .add_systems(
        PostUpdate,
        send.in_set(RenetSend).run_if(resource_exists::<GameTransport>).run_if(resource_exists::<RenetServer>),
    )
    .add_systems(
        Last,
        disconnect_on_exit.run_if(resource_exists::<GameTransport>).run_if(resource_exists::<RenetServer>),
    );
}

fn receive(mut transport: ResMut<GameTransport>, mut renet: ResMut<RenetServer>, time: Res<Time<Real>>) {
    let GameTransport { socket, intake, buffer, bytes } = &mut *transport;
    intake.advance(time.delta());
    let (mut received, mut datagrams) = (0, 0);
    let mut send = counted(socket, bytes);
    let drained = socket::drain(socket, buffer, MAX_DATAGRAMS_PER_FRAME, |from, datagram| {
        received += datagram.len() as u64;
        datagrams += 1;
        // Refusals are counted and logged (throttled) by the intake.
        let _ = intake.receive(from, datagram, &mut renet, &mut send);
    });
    if let Err(e) = drained {
        error!("the game socket failed: {e}");
    }
    intake.update(&mut renet, &mut send);
    drop(send);
    bytes.received += received;
    bytes.datagrams_received += datagrams;
}

fn send(mut transport: ResMut<GameTransport>, mut renet: ResMut<RenetServer>) {
    let GameTransport { socket, intake, bytes, .. } = &mut *transport;
    intake.send_packets(&mut renet, &mut counted(socket, bytes));
}

fn disconnect_on_exit(
    exit: MessageReader<AppExit>,
    mut transport: ResMut<GameTransport>,
    mut renet: ResMut<RenetServer>,
) {
    if !exit.is_empty() {
        let GameTransport { socket, intake, .. } = &mut *transport;
        intake.disconnect_all(&mut renet, &mut send_to(socket));
    }
}
