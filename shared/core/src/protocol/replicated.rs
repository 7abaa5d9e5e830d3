//! Every replicated component, and who may see it.
//!
//! Every replicated entity carries an [`Audience`]; replicon hides an entity from a client whose
//! [`ClientRole`] is not in the audience, and hides entities with no `Audience` at all. (The server adds
//! a second filter of its own, its session tag: a client sees only its own session's entities.) No component here
//! carries (or can be used to infer) which copy is real: all copies of an artifact share one look.

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use glam::{Quat, Vec2, Vec3};
use serde::{Deserialize, Serialize};

use super::ids::{CaseId, GuardId, ItemId, Role};
use crate::artifact::{ArtifactKind, ArtifactLook};

/// Who may see what, component by component: (type name, audience). Kept next to the registrations
/// below so a reviewer sees the whole list in one place.
pub const REPLICATED: &[(&str, &str)] = &[
    ("SessionView", "both"),
    ("ViveAvatar", "both"),
    ("PhantomTool", "both"),
    ("Cases", "both (every display case of the session)"),
    ("Items", "both (copies share one look; no real/fake flag exists)"),
    (
        "Guards",
        "two per session: one for Vive alone with the guards he could see or hear now (the server's \
         interest management), one for Phantom alone with every guard",
    ),
    ("Audience", "both (the visibility filter itself)"),
];

pub(super) fn register(app: &mut App) {
    app.replicate::<SessionView>()
        .replicate::<ViveAvatar>()
        .replicate::<PhantomTool>()
        .replicate::<Cases>()
        .replicate::<Items>()
        .replicate::<Guards>()
        .replicate::<Audience>()
        .add_visibility_filter::<Audience>();
}

/// A session's display cases, in level order: one replicated component for all of them (a server's
/// replication walks entities × clients, so a session replicates few entities). A client spreads it
/// into one local entity per case carrying its [`CaseView`], which is what game code queries.
#[derive(Component, Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Cases(pub Vec<CaseView>);

/// A session's items, in level order; spread on a client into one local [`ItemView`] entity each.
#[derive(Component, Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Items(pub Vec<ItemView>);

/// Guards, in level order; spread on a client into one local [`GuardView`] entity per guard it was
/// sent.
#[derive(Component, Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Guards(pub Vec<GuardView>);

/// Which roles may see a replicated entity.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[component(immutable)]
pub enum Audience {
    /// Both players.
    Both,
    /// Only the given role.
    Only(Role),
}

/// Marks a connected client entity on the server with its role (the client side of [`Audience`]).
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[component(immutable)]
pub struct ClientRole(pub Role);

impl VisibilityFilter for Audience {
    type ClientComponent = ClientRole;
    type Scope = Entity;

    fn is_visible(&self, _client: Entity, role: Option<&ClientRole>) -> bool {
        match (self, role) {
            (_, None) => false,
            (Audience::Both, Some(_)) => true,
            (Audience::Only(r), Some(ClientRole(c))) => r == c,
        }
    }
}

/// Session phase.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Phase {
    /// Waiting for both players.
    #[default]
    Lobby,
    /// The heist is on; the timer runs.
    Heist,
    /// Every target secured in time.
    Won,
    /// Lost, with the reason.
    Lost(LossReason),
}

/// Why a heist was lost.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum LossReason {
    /// A guard caught Vive.
    Caught,
    /// The timer ran out.
    Time,
    /// Too many wrong verdicts: the museum locked down.
    Alarm,
    /// A player left during the heist.
    Abandoned,
}

impl std::fmt::Display for LossReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LossReason::Caught => "caught",
            LossReason::Time => "time",
            LossReason::Alarm => "alarm",
            LossReason::Abandoned => "abandoned",
        })
    }
}

/// The session as both players see it.
#[derive(Component, Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SessionView {
    /// Current phase.
    pub phase: Phase,
    /// Seconds of game time left (the limit while in the lobby).
    pub time_left_s: f32,
    /// Alarm level, 0 ..= [`crate::rules::ALARM_LOCKDOWN`].
    pub alarm: u8,
    /// Target artifacts, in level order, with whether each is secured.
    pub targets: Vec<(ArtifactKind, bool)>,
    /// Which roles are connected.
    pub present: (bool, bool),
    /// The session's difficulty (with the level, it says what the guards can do: `Level::tuning`).
    pub difficulty: crate::rules::Difficulty,
}

/// Vive's stance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Stance {
    /// Standing still or walking.
    #[default]
    Standing,
    /// Running.
    Running,
    /// Crouching.
    Crouching,
}

/// Vive's avatar.
#[derive(Component, Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ViveAvatar {
    /// Position on the floor plane, metres.
    pub position: Vec2,
    /// Velocity, m/s.
    pub velocity: Vec2,
    /// Facing yaw, radians.
    pub facing: f32,
    /// Stance.
    pub stance: Stance,
    /// Carried items (at most [`crate::rules::CARRY_LIMIT`]).
    pub carrying: Vec<ItemId>,
    /// Last movement input the server applied (for client-side reconciliation).
    pub last_input_seq: u32,
}

/// A guard's alert state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum GuardAlert {
    /// Walking the patrol route.
    #[default]
    Patrolling,
    /// Saw or heard something; turning towards it.
    Suspicious,
    /// Walking to where the noise or sighting was.
    Investigating,
    /// Running after Vive.
    Chasing,
    /// Going back to the patrol route.
    Returning,
    /// Searching the rooms around where Vive was seen (after a chase, or called by radio).
    Searching,
}

/// A guard (on a client, a local entity spread from [`Guards`]).
#[derive(Component, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GuardView {
    /// Which guard.
    pub id: GuardId,
    /// Name, for speech ("Bruno").
    pub name: String,
    /// Position, metres.
    pub position: Vec2,
    /// Facing yaw, radians.
    pub facing: f32,
    /// Alert state.
    pub alert: GuardAlert,
}

/// A display case (on a client, a local entity spread from [`Cases`]).
#[derive(Component, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaseView {
    /// Which case.
    pub id: CaseId,
    /// Position, metres.
    pub position: Vec2,
    /// True once shattered.
    pub broken: bool,
}

/// What an item is, as anyone can see it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ItemKind {
    /// A copy of a target artifact: only the shared look, never the copy's traits.
    Copy {
        /// Which artifact it is a copy of.
        artifact: ArtifactKind,
        /// The look shared by all its copies.
        look: ArtifactLook,
    },
    /// A worthless object to throw.
    Prop,
}

/// Where an item is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ItemPlace {
    /// Inside an intact or broken display case.
    InCase(CaseId),
    /// Lying on the floor.
    Floor(Vec2),
    /// Carried by Vive.
    Carried,
    /// On Phantom's workbench, being examined.
    Workbench,
    /// Judged real and right: in the bag.
    Secured,
    /// Judged fake and right: thrown away.
    Discarded,
}

/// An item (on a client, a local entity spread from [`Items`]).
#[derive(Component, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ItemView {
    /// Which item.
    pub id: ItemId,
    /// What it is.
    pub kind: ItemKind,
    /// Where it is.
    pub place: ItemPlace,
}

/// Phantom's tool as last reported (workbench frame), for the VR client to draw.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PhantomTool {
    /// Tool tip, metres.
    pub position: Vec3,
    /// Orientation.
    pub rotation: Quat,
}
