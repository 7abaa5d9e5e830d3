//! What the server told this client, kept for the app's systems to read.

use bevy::prelude::*;
use heist_shared::artifact::Briefing;
use heist_shared::level::Level;
use heist_shared::protocol::{DisconnectReason, GameEvent, Refusal, Role, SeatTicket, WorkbenchCopy};

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
    /// Game events not yet taken by the app, oldest first: at most [`Inbox::KEPT_EVENTS`] (an app that
    /// never takes them, a bot, loses the oldest rather than growing without end).
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
    /// Untaken events kept at most: past twice this many, the oldest half goes.
    pub const KEPT_EVENTS: usize = 1024;

    /// Keeps `event` for the app, forgetting the oldest past [`Inbox::KEPT_EVENTS`].
    pub fn keep_event(&mut self, event: GameEvent) {
        if self.events.len() >= 2 * Self::KEPT_EVENTS {
            self.events.drain(..Self::KEPT_EVENTS);
        }
        self.events.push(event);
    }

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_inbox_nobody_empties_keeps_the_newest_events_and_stays_bounded() {
        let mut inbox = Inbox::default();
        for n in 0..10_000u32 {
            inbox.keep_event(GameEvent::RoundStarted(n));
            assert!(inbox.events.len() <= 2 * Inbox::KEPT_EVENTS);
        }
        assert!(inbox.events.len() >= Inbox::KEPT_EVENTS);
        assert_eq!(inbox.events.last(), Some(&GameEvent::RoundStarted(9_999)), "the newest is kept");
        let oldest = 10_000 - inbox.events.len() as u32;
        assert_eq!(inbox.events[0], GameEvent::RoundStarted(oldest), "in order, the oldest forgotten first");
    }
}
