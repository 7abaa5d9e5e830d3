//! Messages from a client to the server, grouped by phase and role.

use bevy::prelude::*;
use bevy_replicon::{
    bytes::Bytes,
    postcard,
    shared::message::ctx::{ClientSendCtx, ServerReceiveCtx},
};
use glam::{Quat, Vec2, Vec3};
use serde::{Deserialize, Serialize};

use super::ids::{CaseId, ItemId};

/// Everything a client can say.
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ClientMsg {
    /// Before the heist starts.
    Lobby(LobbyMsg),
    /// Vive's intents and actions.
    Vive(ViveMsg),
    /// Phantom's actions.
    Phantom(PhantomMsg),
    /// Bytes that did not decode (created by the server's decoder, never sent): refused with the reason.
    Malformed(String),
}

/// Lobby phase.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum LobbyMsg {
    /// The player is ready; the heist starts once both players are present and ready.
    Ready,
    /// After a result: the player wants another round (new seed, same roles, same join code); it starts
    /// as soon as both players have asked.
    Rematch,
    /// The player is leaving on purpose (the partner hears "left", not "dropped"); the server then closes
    /// the connection.
    Leave,
}

/// Vive's movement gait.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Gait {
    /// Normal walk (quiet).
    #[default]
    Walk,
    /// Run (fast, loud footsteps).
    Run,
    /// Crouch (slow, silent, harder to see).
    Crouch,
}

/// Vive's intents (heist phase).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ViveMsg {
    /// Movement intent for the coming ticks: `direction` on the floor plane with length <= 1
    /// (a fraction of the gait's top speed). `seq` increases by one per input, for reconciliation.
    Move {
        /// Input sequence number.
        seq: u32,
        /// Desired direction, |direction| <= 1.
        direction: Vec2,
        /// Gait.
        gait: Gait,
        /// Facing yaw, radians (0 = +x, counter-clockwise towards +z).
        facing: f32,
    },
    /// Break a display case within reach.
    Break(CaseId),
    /// Pick up an item within reach (a copy out of a broken case, or a prop).
    PickUp(ItemId),
    /// Drop a carried item at Vive's feet.
    Drop(ItemId),
    /// Throw a carried item towards a point (lands at most the throw range away, makes noise there).
    Throw {
        /// The carried item.
        item: ItemId,
        /// Aim point on the floor plane.
        target: Vec2,
    },
    /// Place a carried copy on Phantom's workbench (within reach of it).
    PlaceOnWorkbench(ItemId),
    /// Vive's client has shown Phantom's warning (sent by the client itself, so Phantom knows it arrived).
    WarningSeen(WarningKind),
}

/// What Phantom warns Vive about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum WarningKind {
    /// Freeze: a guard is close.
    Hide,
    /// The way is clear.
    Go,
    /// Come back to the workbench.
    ComeBack,
}

/// Phantom's actions (heist phase).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum PhantomMsg {
    /// The verdict on the copy on the workbench.
    Verdict {
        /// The copy being judged (must be the one on the workbench).
        item: ItemId,
        /// True when Phantom declares it the real one.
        real: bool,
    },
    /// Where Phantom's tool is, for the VR client to draw (workbench frame, metres).
    ToolPose {
        /// Tool tip position.
        position: Vec3,
        /// Tool orientation.
        rotation: Quat,
    },
    /// A warning relayed to Vive.
    Warn(WarningKind),
}

pub(super) fn serialize(_ctx: &mut ClientSendCtx<'_>, msg: &ClientMsg, out: &mut Vec<u8>) -> Result<()> {
    bevy_replicon::postcard_utils::to_extend_mut(msg, out)?;
    Ok(())
}

/// Never fails: bytes that do not decode become [`ClientMsg::Malformed`], so the server can refuse
/// them with a reason and count them against the sender instead of dropping them silently.
pub(super) fn deserialize(_ctx: &mut ServerReceiveCtx<'_>, bytes: &mut Bytes) -> Result<ClientMsg> {
    let all = std::mem::take(bytes);
    Ok(decode(&all))
}

/// Decodes one client message; anything that is not exactly one valid message becomes `Malformed`.
pub fn decode(bytes: &[u8]) -> ClientMsg {
    match postcard::take_from_bytes::<ClientMsg>(bytes) {
        Ok((ClientMsg::Malformed(_), _)) => ClientMsg::Malformed("clients may not send `Malformed`".into()),
        Ok((msg, [])) => msg,
        Ok((_, rest)) => ClientMsg::Malformed(format!("{} trailing bytes after the message", rest.len())),
        Err(e) => ClientMsg::Malformed(format!("undecodable message ({} bytes): {e}", bytes.len())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_valid_message_round_trips() {
        let msg = ClientMsg::Vive(ViveMsg::Throw { item: ItemId(3), target: Vec2::new(1.0, 2.0) });
        let bytes = postcard::to_allocvec(&msg).unwrap();
        assert_eq!(decode(&bytes), msg);
    }

    #[test]
    fn a_client_cannot_forge_a_malformed_message() {
        let bytes = postcard::to_allocvec(&ClientMsg::Malformed("x".into())).unwrap();
        assert!(matches!(decode(&bytes), ClientMsg::Malformed(r) if r.contains("may not send")));
    }

    proptest! {
        #[test]
        fn arbitrary_bytes_never_panic_the_decoder(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
            let _ = decode(&bytes);
        }
    }
}
