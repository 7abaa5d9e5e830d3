//! The client core both Phantom Heist clients (and the bots) stand on: exchange a join code for a
//! connect token, connect over netcode/UDP, keep the latest server messages, send intents.
//!
//! It adds no rendering, audio or input: a client app adds [`ClientNetPlugin`], calls [`connect`] with a
//! token from [`request_token`], then reads the replicated components (`heist_shared::protocol`) and
//! [`Inbox`], and writes `ClientMsg` messages.
#![warn(missing_docs)]

mod error;
pub mod notice;
pub mod rejoin;
pub mod seats;
pub mod signals;
mod token;
pub mod transport;

pub use error::JoinError;
pub use heist_transport::renetcode::ConnectToken;
pub use rejoin::{Reconnect, Rejoin};
pub use seats::{Joining, SeatCache, SeatKeeper, hold_seat, join_or_resume};
pub use token::{create_session, request_resume_token, request_token};

use std::time::{SystemTime, UNIX_EPOCH};

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use bevy_replicon_renet::RenetChannelsExt;
use bevy_replicon_renet::renet::ConnectionConfig;
use heist_shared::artifact::Briefing;
use heist_shared::level::Level;
use heist_shared::protocol::{DisconnectReason, GameEvent, Refusal, Role, SeatTicket, ServerMsg, WorkbenchCopy};
use heist_transport::renetcode::ClientAuthentication;

/// What the server has told this client, kept for the app's systems to read.
#[derive(Resource, Default, Debug)]
pub struct Inbox {
    /// The role granted by the server (after `Welcome`).
    pub role: Option<Role>,
    /// The level the server plays (after `Welcome`).
    pub level: Option<Level>,
    /// Briefings (Phantom only).
    pub briefings: Vec<Briefing>,
    /// The latest copy on the workbench not yet taken by the app (Phantom only).
    pub workbench: Option<WorkbenchCopy>,
    /// Game events not yet taken by the app, oldest first.
    pub events: Vec<GameEvent>,
    /// Every refusal received.
    pub refusals: Vec<Refusal>,
    /// Why the server disconnected us, if it said so.
    pub disconnect: Option<DisconnectReason>,
    /// Our seat's ticket (after `Welcome`): what takes the seat back after a lost connection.
    pub seat: Option<SeatTicket>,
    /// True when the last `Welcome` took a kept seat back.
    pub resumed: bool,
    /// The last `RoundStarted` (0 before one: a session's first round sends none; [`Inbox::current_round`]
    /// reads it). A new round clears the briefings and the workbench.
    pub round: u32,
    /// Count of each kind of message received, for tests: (welcome, briefings, workbench, events).
    pub received: MessageCounts,
}

impl Inbox {
    /// The round being played: 1 until a `RoundStarted` says otherwise.
    pub fn current_round(&self) -> u32 {
        self.round.max(1)
    }
}

/// How many server messages of each kind arrived.
#[derive(Default, Debug, Clone, Copy, PartialEq, Eq)]
pub struct MessageCounts {
    /// `Welcome`.
    pub welcome: u32,
    /// `Briefings`.
    pub briefings: u32,
    /// `Workbench`.
    pub workbench: u32,
    /// `Event`.
    pub events: u32,
}

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
            .add_systems(Update, (leave, seats::keep_seat));
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
                inbox.events.push(e);
                inbox.received.events += 1;
            }
        }
    }
}

/// Seconds of silence from the server after which the connection counts as lost (netcode sends a
/// keep-alive several times a second when there is nothing else to send).
pub const SILENCE_LOST_S: f64 = 3.0;

/// The connection to the server, as the player should hear of it.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Link {
    /// Nothing heard from the server yet.
    #[default]
    Connecting,
    /// The server was heard within [`SILENCE_LOST_S`].
    Up,
    /// Silent for [`SILENCE_LOST_S`] or more: the connection may come back until netcode gives up.
    Silent,
    /// The transport stopped: the server let us go, or went silent until netcode's timeout (6 s).
    Gone,
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

/// Leaving on purpose: set [`Leaving::since`] (or call [`Leaving::start`]) and the client says `Leave` to
/// the server (so the partner hears "left", not "dropped"), waits for the server to close the connection
/// (at most [`LEAVE_WAIT_S`]) and exits the app.
#[derive(Resource, Default, Debug)]
pub struct Leaving {
    /// When the player asked to leave (app time, seconds); `None` while staying.
    pub since: Option<f64>,
    sent: bool,
}

/// Seconds a leaving client waits for the server to let it go before exiting anyway.
pub const LEAVE_WAIT_S: f64 = 1.0;

impl Leaving {
    /// Starts leaving now (`now`: the app's real time, seconds).
    pub fn start(&mut self, now: f64) {
        self.since.get_or_insert(now);
    }
}

fn leave(
    mut leaving: ResMut<Leaving>,
    inbox: Res<Inbox>,
    time: Res<Time<Real>>,
    mut out: MessageWriter<heist_shared::protocol::ClientMsg>,
    mut exit: MessageWriter<AppExit>,
) {
    let Some(since) = leaving.since else { return };
    if !leaving.sent {
        leaving.sent = true;
        out.write(heist_shared::protocol::ClientMsg::Lobby(heist_shared::protocol::LobbyMsg::Leave));
    }
    if inbox.disconnect.is_some() || time.elapsed_secs_f64() - since > LEAVE_WAIT_S {
        exit.write(AppExit::Success);
    }
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
