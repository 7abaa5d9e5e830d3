//! The client core both Phantom Heist clients (and the bots) stand on: exchange a join code for a
//! connect token, connect over netcode/UDP, keep the latest server messages, send intents.
//!
//! It adds no rendering, audio or input: a client app adds [`ClientNetPlugin`], calls [`connect`] with a
//! token from [`request_token`], then reads the replicated components (`heist_shared::protocol`) and
//! [`Inbox`], and writes `ClientMsg` messages.
#![warn(missing_docs)]

mod error;
mod inbox;
mod link;
pub mod notice;
pub mod rejoin;
pub mod seats;
pub mod signals;
mod token;
pub mod transport;

pub use error::JoinError;
pub use heist_transport::renetcode::ConnectToken;
pub use inbox::{Inbox, MessageCounts};
pub use link::{LEAVE_WAIT_S, Leaving, Link, SILENCE_LOST_S};
pub use rejoin::{Reconnect, Rejoin};
pub use seats::{Joining, SeatCache, SeatKeeper, hold_seat, join_or_resume};
pub use token::{create_session, request_resume_token, request_token};
pub use transport::connection_config;

use std::time::{SystemTime, UNIX_EPOCH};

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use heist_shared::protocol::{GameEvent, Role, ServerMsg};
use heist_transport::renetcode::ClientAuthentication;

/// System sets of the client core.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum ClientNetSystems {
    /// `PreUpdate`, after replicon's receive: server messages into [`Inbox`].
    Receive,
}

/// Adds replicon + renet (client side) and the protocol, and fills [`Inbox`].
pub struct ClientNetPlugin;

impl Plugin for ClientNetPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<bevy::state::app::StatesPlugin>() {
            app.add_plugins(bevy::state::app::StatesPlugin);
        }
        app.add_plugins((RepliconPlugins, bevy_replicon_renet::RepliconRenetPlugins))
            .add_plugins(heist_shared::protocol::ProtocolPlugin)
            .init_resource::<Inbox>()
            .init_resource::<Leaving>()
            .init_resource::<Link>()
            .init_resource::<Reconnect>()
            .configure_sets(PreUpdate, ClientNetSystems::Receive.after(ClientSystems::Receive))
            .add_systems(PreUpdate, (fill_inbox, watch_link, rejoin::drive).chain().in_set(ClientNetSystems::Receive))
            .add_systems(Update, (link::leave, seats::keep_seat));
        transport::add_systems(app);
    }
}

/// Server messages into [`Inbox`]; as Vive, a warning from Phantom is acknowledged at once (Phantom hears
/// that it arrived).
fn fill_inbox(
    mut messages: MessageReader<ServerMsg>,
    mut inbox: ResMut<Inbox>,
    mut out: MessageWriter<heist_shared::protocol::ClientMsg>,
) {
    for msg in messages.read() {
        if let ServerMsg::Event(GameEvent::Warning(w)) = msg
            && inbox.role == Some(Role::Vive)
        {
            out.write(heist_shared::protocol::ClientMsg::Vive(heist_shared::protocol::ViveMsg::WarningSeen(*w)));
        }
        match msg.clone() {
            ServerMsg::Welcome { role, level, seat, resumed } => {
                inbox.role = Some(role);
                inbox.level = Some(*level);
                inbox.seat = Some(seat);
                inbox.resumed = resumed;
                inbox.received.welcome += 1;
            }
            ServerMsg::Refused(r) => inbox.refusals.push(r),
            ServerMsg::Disconnecting(reason) => inbox.disconnect = Some(reason),
            ServerMsg::Briefings(b) => {
                inbox.briefings = b;
                inbox.received.briefings += 1;
            }
            ServerMsg::Workbench(copy) => {
                inbox.workbench = Some(copy);
                inbox.received.workbench += 1;
            }
            ServerMsg::Event(e) => {
                if let GameEvent::RoundStarted(n) = e {
                    inbox.round = n;
                    inbox.briefings.clear();
                    inbox.workbench = None;
                }
                inbox.keep_event(e);
                inbox.received.events += 1;
            }
        }
    }
}

/// Updates [`Link`] from the transport (only on a change, so `is_changed` means a new state).
fn watch_link(transport: Option<Res<transport::ClientTransport>>, time: Res<Time<Real>>, mut link: ResMut<Link>) {
    let Some(transport) = transport else { return };
    let state = if transport.stopped.is_some() {
        Link::Gone
    } else {
        match transport.heard_at {
            None => Link::Connecting,
            Some(at) if (time.elapsed() - at).as_secs_f64() >= SILENCE_LOST_S => Link::Silent,
            Some(_) => Link::Up,
        }
    };
    if *link != state {
        *link = state;
    }
}

/// True once this client's connection is over for good: the server said why, coming back failed, or the
/// link is gone and no way back is being tried (no [`Rejoin`], or the loss had a reason).
pub fn connection_over(link: Link, inbox: &Inbox, reconnect: &Reconnect) -> bool {
    inbox.disconnect.is_some()
        || matches!(reconnect, Reconnect::GaveUp(_))
        || (link == Link::Gone && !reconnect.is_trying())
}

/// Creates the netcode transport for `token` (call after [`ClientNetPlugin`] is added and all protocol
/// registration is done, before the first update).
pub fn connect(app: &mut App, token: ConnectToken) -> Result<(), JoinError> {
    let (renet, transport) = transport::open_with_token(token, app.world().resource::<RepliconChannels>())?;
    app.insert_resource(renet).insert_resource(transport);
    Ok(())
}

/// Connects without a token (the server must run with `--insecure`), claiming `role`.
pub fn connect_insecure(app: &mut App, server: std::net::SocketAddr, role: Role) -> Result<(), JoinError> {
    let user_data = heist_shared::protocol::TokenUserData { role, session: 0, ticket: None }.encode();
    let client_id = SystemTime::now().duration_since(UNIX_EPOCH).unwrap_or_default().as_nanos() as u64;
    let auth = ClientAuthentication::Unsecure {
        protocol_id: heist_shared::protocol::PROTOCOL_ID,
        client_id,
        server_addr: server,
        user_data: Some(user_data),
    };
    let (renet, transport) = transport::open(server, auth, app.world().resource::<RepliconChannels>())?;
    app.insert_resource(renet).insert_resource(transport);
    Ok(())
}
