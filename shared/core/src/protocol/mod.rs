//! The network protocol: one message enum per direction, the rule of who may send what when,
//! the channels, the replicated components, and the plugin that registers all of it.
//!
//! Server and clients must add [`ProtocolPlugin`] in the same order so their protocol hashes match.

mod client_msg;
mod ids;
pub mod join;
mod replicated;
mod server_msg;
mod spread;
mod token;
mod verify;
pub mod voice;

pub use client_msg::{ClientMsg, Gait, LobbyMsg, PhantomMsg, ViveMsg, WarningKind, decode as decode_client_msg};
pub use ids::{CaseId, GuardId, ItemId, Role};
pub use replicated::{
    Audience, CaseView, Cases, ClientRole, GuardAlert, GuardView, Guards, ItemKind, ItemPlace, ItemView, Items,
    LossReason, PhantomTool, Phase, REPLICATED, SessionView, Stance, ViveAvatar,
};
pub use server_msg::{
    DisconnectReason, GameEvent, NoiseKind, RadioAbout, Refusal, ServerMsg, VerdictOutcome, WorkbenchCopy,
};
pub use spread::{Spread, SpreadSystems};
pub use token::{SeatTicket, TokenUserData, USER_DATA_MAGIC};
pub use verify::verify;
pub use voice::{ClientVoice, PartnerVoice, VoiceFrame};

use bevy::prelude::*;
use bevy_replicon::prelude::*;

/// Netcode protocol id: bumps whenever the wire format changes (3: renet's packets of a frame travel
/// bundled, heist_transport::bundle).
pub const PROTOCOL_ID: u64 = 0x5048_4549_5354_0003;

/// Server simulation rate (FixedUpdate), Hz.
pub const TICK_HZ: f64 = 60.0;

/// The transport channels the game uses, and what travels on each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GameChannel {
    /// Client intents and actions, server replies and events: reliable and ordered, so an action is
    /// never lost or applied before the movement that brought the player in reach.
    Commands,
    /// The walkie-talkie's voice frames (one channel each way): unreliable, so a lost frame is
    /// concealed by the receiver instead of resent late, and nothing on it waits for anything else.
    Voice,
}

impl GameChannel {
    /// The replicon channel this maps to.
    pub const fn replicon(self) -> Channel {
        match self {
            GameChannel::Commands => Channel::Ordered,
            GameChannel::Voice => Channel::Unreliable,
        }
    }
}

/// Registers every replicated component and remote message, in a fixed order.
pub struct ProtocolPlugin;

impl Plugin for ProtocolPlugin {
    fn build(&self, app: &mut App) {
        replicated::register(app);
        spread::add_systems(app);
        app.add_client_message_with::<ClientMsg>(
            GameChannel::Commands.replicon(),
            client_msg::serialize,
            client_msg::deserialize,
        )
        .add_server_message::<ServerMsg>(GameChannel::Commands.replicon())
        .make_message_independent::<ServerMsg>()
        .add_client_message_with::<ClientVoice>(GameChannel::Voice.replicon(), voice::serialize, voice::deserialize)
        .add_server_message::<PartnerVoice>(GameChannel::Voice.replicon())
        .make_message_independent::<PartnerVoice>();
    }
}
