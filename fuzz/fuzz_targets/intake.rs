//! The server's whole intake under arbitrary traffic: datagrams from an unknown, a pending and a connected
//! address, and renet packets and bundles of them sealed with the connected client's key (the only way
//! random bytes get past netcode's encryption to renet), then every message renet delivers through the
//! server's `ClientMsg` decoder (and what arrives on the voice channel through the `ClientVoice`
//! decoder). The channels are the game's own, from its registered protocol.
//!
//! `cargo fuzz run intake` (see README, "Fuzzing").
#![no_main]

use std::net::SocketAddr;
use std::sync::OnceLock;

use arbitrary::Arbitrary;
use bevy::prelude::*;
use bevy_replicon::prelude::*;
use bevy_replicon::shared::message::registry::RemoteMessageRegistry;
use heist_shared::protocol::{ClientMsg, ClientVoice, ProtocolPlugin, decode_client_msg};
use heist_transport::IntakeLimits;
use heist_transport::memory::{MemoryServer, RawClient};
use heist_transport::renet::ConnectionConfig;
use libfuzzer_sys::fuzz_target;

/// One thing the traffic does.
#[derive(Arbitrary, Debug)]
enum Op {
    /// A datagram from an address netcode has never seen.
    Unknown(Vec<u8>),
    /// A datagram from the address that sent a connection request and never answered the challenge.
    Pending(Vec<u8>),
    /// A datagram from the connected client's address.
    Connected(Vec<u8>),
    /// A renet packet, alone in a bundle, sealed with the connected client's session key.
    Sealed(Vec<u8>),
    /// Any payload (a bundle of renet packets, well-formed or not) sealed with that key.
    SealedBundle(Vec<u8>),
    /// A server frame: renet's clock, keep-alives, disconnections, sends.
    Frame,
}

/// The game's renet channels and the channels `ClientMsg` and `ClientVoice` travel on.
struct Protocol {
    config: ConnectionConfig,
    client_channels: u8,
    messages: u8,
    voice: u8,
}

fn protocol() -> &'static Protocol {
    static PROTOCOL: OnceLock<Protocol> = OnceLock::new();
    PROTOCOL.get_or_init(|| {
        let mut app = App::new();
        app.add_plugins((MinimalPlugins, bevy::state::app::StatesPlugin, RepliconPlugins, ProtocolPlugin));
        let channels = app.world().resource::<RepliconChannels>();
        let config = heist_client::connection_config(channels);
        let client_channels = config.client_channels_config.len() as u8;
        let messages = app
            .world()
            .resource::<RemoteMessageRegistry>()
            .client_message_channel::<ClientMsg>()
            .expect("ClientMsg is registered") as u8;
        let voice = app
            .world()
            .resource::<RemoteMessageRegistry>()
            .client_message_channel::<ClientVoice>()
            .expect("ClientVoice is registered") as u8;
        Protocol { config, client_channels, messages, voice }
    })
}

const PENDING: SocketAddr = SocketAddr::V4(std::net::SocketAddrV4::new(std::net::Ipv4Addr::new(10, 0, 0, 2), 2000));
const CONNECTED: SocketAddr = SocketAddr::V4(std::net::SocketAddrV4::new(std::net::Ipv4Addr::new(10, 0, 0, 3), 3000));
const UNKNOWN: SocketAddr = SocketAddr::V4(std::net::SocketAddrV4::new(std::net::Ipv4Addr::new(10, 0, 0, 9), 9000));

fuzz_target!(|ops: Vec<Op>| {
    let protocol = protocol();
    let mut server = MemoryServer::with(protocol.config.clone(), IntakeLimits::default());
    let _pending = RawClient::pending(&mut server, PENDING, 2);
    let mut connected = RawClient::connected(&mut server, CONNECTED, 3);
    for op in ops.into_iter().take(64) {
        let _ = match op {
            Op::Unknown(d) => server.deliver(UNKNOWN, &d),
            Op::Pending(d) => server.deliver(PENDING, &d),
            Op::Connected(d) => server.deliver(CONNECTED, &d),
            Op::Sealed(p) => {
                let d = connected.seal(&p);
                server.deliver(CONNECTED, &d)
            }
            Op::SealedBundle(b) => {
                let d = connected.seal_bundle(&b);
                server.deliver(CONNECTED, &d)
            }
            Op::Frame => {
                server.frame();
                Ok(())
            }
        };
    }
    server.frame();
    for client in server.renet.clients_id() {
        for channel in 0..protocol.client_channels {
            while let Some(message) = server.renet.receive_message(client, channel) {
                if channel == protocol.messages {
                    let _ = decode_client_msg(&message);
                } else if channel == protocol.voice {
                    let _ = heist_shared::protocol::voice::decode(&message);
                }
            }
        }
    }
});
