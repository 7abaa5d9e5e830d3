//! Messages from the server to a client.

use bevy::prelude::*;
use glam::Vec2;
use serde::{Deserialize, Serialize};

use super::client_msg::WarningKind;
use super::ids::{CaseId, GuardId, ItemId, Role};
use super::replicated::{GuardAlert, Phase};
use super::token::SeatTicket;
use crate::artifact::{Briefing, HapticMesh, Material};

/// Everything the server can say to one client.
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ServerMsg {
    /// Sent once after the connection is accepted.
    Welcome {
        /// The role the token granted.
        role: Role,
        /// The level being played (walls, doors, cases, routes).
        level: Box<crate::level::Level>,
        /// This seat's ticket: keep it (the seat cache) to take the seat back after a lost connection.
        seat: SeatTicket,
        /// True when this connection took back a held seat (the session's news follows: briefings, the
        /// copy on the bench); Vive's move numbers start afresh at 1 on every connection.
        resumed: bool,
    },
    /// An input was refused; nothing changed.
    Refused(Refusal),
    /// The server is about to disconnect this client.
    Disconnecting(DisconnectReason),
    /// Phantom only: the spoken description of each target's real copy.
    Briefings(Vec<Briefing>),
    /// Phantom only: the copy now on the workbench, with its true geometry and material (no label).
    Workbench(WorkbenchCopy),
    /// Something happened that players should hear about.
    Event(GameEvent),
}

/// A copy's touchable truth, sent only to Phantom and only while it lies on the workbench.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorkbenchCopy {
    /// The copy.
    pub item: ItemId,
    /// Closed triangle mesh, metres, in the workbench frame.
    pub mesh: HapticMesh,
    /// What its surface feels like.
    pub material: Material,
}

/// Result of a verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum VerdictOutcome {
    /// Real, declared real: the target is secured.
    Secured,
    /// Fake, declared fake: thrown away.
    Discarded,
    /// Wrong: the alarm rises and the copy stays on the workbench.
    Wrong,
}

/// What makes a noise.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum NoiseKind {
    /// Running footsteps.
    Footsteps,
    /// A display case shattering.
    Glass,
    /// A thrown object landing.
    Thud,
    /// The alarm bell.
    Alarm,
}

/// What a guard radios about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum RadioAbout {
    /// He is sure he saw an intruder.
    Sighting,
    /// He found a broken display case.
    Evidence,
}

impl RadioAbout {
    /// How many spots the guards who answer such a call search between them: around a sighting the spot
    /// and the rooms next to it ([`crate::rules::SEARCH_SPOTS`]), around a broken case the case and the
    /// nearest room next to it ([`crate::rules::EVIDENCE_SPOTS`]).
    pub fn search_spots(self) -> usize {
        match self {
            RadioAbout::Sighting => crate::rules::SEARCH_SPOTS,
            RadioAbout::Evidence => crate::rules::EVIDENCE_SPOTS,
        }
    }
}

/// Something that happened, for logs, speech and sound.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum GameEvent {
    /// The phase changed.
    PhaseChanged(Phase),
    /// A guard's alert state changed.
    GuardAlert {
        /// Which guard.
        guard: GuardId,
        /// New state.
        alert: GuardAlert,
        /// Where the guard is.
        position: Vec2,
    },
    /// A noise was made.
    Noise {
        /// What made it.
        kind: NoiseKind,
        /// Where.
        position: Vec2,
        /// Audible radius, metres.
        loudness: f32,
    },
    /// A case was broken.
    CaseBroken(CaseId),
    /// A copy was placed on the workbench.
    Delivered(ItemId),
    /// A verdict was given.
    Verdict {
        /// The copy.
        item: ItemId,
        /// Declared real?
        declared_real: bool,
        /// What came of it.
        outcome: VerdictOutcome,
    },
    /// The alarm level changed.
    Alarm(u8),
    /// Phantom warns Vive (sent to both: to Phantom it confirms the warning went out).
    Warning(WarningKind),
    /// Vive's client has shown Phantom's warning (sent to Phantom only).
    WarningSeen(WarningKind),
    /// A player came into the session (the first time or again).
    Joined(Role),
    /// A player whose connection was lost took their seat back.
    Resumed(Role),
    /// A dropped player's seat was kept for [`crate::rules::SEAT_HOLD_S`] and they did not come back: the
    /// seat is free again (and a running heist is lost, abandoned).
    GaveUp(Role),
    /// A player went away: `dropped` when the connection was lost rather than closed by the player (a
    /// dropped player's seat is then kept for them, and a running heist pauses until they are back).
    Left {
        /// Who.
        role: Role,
        /// Lost connection (true) or closed by the player (false).
        dropped: bool,
    },
    /// After a result, a player asked for another round.
    RematchAsked(Role),
    /// A new round began (the first round is 1): forget the last round's copies and briefings.
    RoundStarted(u32),
    /// The session ends in this many seconds unless someone asks for another round.
    EndingSoon(u32),
    /// The server is shutting down: a running heist may finish, within this many seconds at most; no
    /// new round begins after it.
    ServerClosing {
        /// Seconds the server waits for the heist at most.
        within_s: u32,
    },
    /// Vive picked an item up.
    PickedUp(ItemId),
    /// A guard radioed the others (heard as a squawk where he stands); those within range come to search
    /// around `at` after the radio's delay.
    Radio {
        /// Who called.
        guard: GuardId,
        /// What about.
        about: RadioAbout,
        /// Where (the intruder's last known position, or the broken case).
        at: Vec2,
        /// Where the caller stands.
        from: Vec2,
        /// The guards who will answer the call.
        answering: Vec<GuardId>,
    },
}

/// Why an input was refused. Sent as data; the session goes on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Refusal {
    /// The bytes were not a valid message.
    Malformed(String),
    /// That message belongs to the other role.
    WrongRole,
    /// Not allowed in the current phase.
    WrongPhase(Phase),
    /// A movement faster than allowed (|direction| > 1).
    TooFast,
    /// A number was NaN or infinite.
    NotFinite,
    /// The target is too far away.
    OutOfReach,
    /// No such case, item or target.
    Unknown,
    /// The case is already broken.
    AlreadyBroken,
    /// The case is intact: break it first.
    CaseIntact,
    /// Vive already carries as much as allowed.
    HandsFull,
    /// Vive does not carry that item.
    NotCarried,
    /// Only artifact copies go on the workbench.
    NotACopy,
    /// Something already lies on the workbench.
    WorkbenchBusy,
    /// The verdict names something that is not on the workbench.
    NotOnWorkbench,
    /// Too many messages this second.
    RateLimited,
    /// The heist is paused while a player is away.
    Paused,
}

impl Refusal {
    /// A short name of the kind of refusal, for metrics and logs (`too_fast`, `wrong_phase`, …).
    pub fn kind(&self) -> &'static str {
        match self {
            Refusal::Malformed(_) => "malformed",
            Refusal::WrongRole => "wrong_role",
            Refusal::WrongPhase(_) => "wrong_phase",
            Refusal::TooFast => "too_fast",
            Refusal::NotFinite => "not_finite",
            Refusal::OutOfReach => "out_of_reach",
            Refusal::Unknown => "unknown",
            Refusal::AlreadyBroken => "already_broken",
            Refusal::CaseIntact => "case_intact",
            Refusal::HandsFull => "hands_full",
            Refusal::NotCarried => "not_carried",
            Refusal::NotACopy => "not_a_copy",
            Refusal::WorkbenchBusy => "workbench_busy",
            Refusal::NotOnWorkbench => "not_on_workbench",
            Refusal::RateLimited => "rate_limited",
            Refusal::Paused => "paused",
        }
    }
}

/// Why the server disconnects a client.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DisconnectReason {
    /// The role in the token is already played by someone else.
    RoleTaken(Role),
    /// The token's user data is not ours or names another session.
    BadToken,
    /// Too many refused or malformed messages.
    Abuse,
    /// The session is over: nobody asked for another round in time, or nobody was left in it.
    SessionEnded,
    /// The seat is kept for the player who dropped from it; only their seat ticket takes it.
    SeatHeld(Role),
    /// The token's seat ticket is not that seat's (or no seat is kept for it).
    BadSeat,
    /// The seat's holder came back on another connection, which replaces this one.
    Replaced,
    /// The server is shutting down (its heists had their time to finish).
    ServerShutdown,
}
