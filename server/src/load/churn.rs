//! Players coming and going during a load run (`heist-server load --churn S`): every S seconds of game
//! time each session, in turn, has one of three things happen to it — Vive's client dies without a word
//! and a new one takes the seat back with its ticket [`AWAY_S`] later; the same for Phantom; or both
//! players leave on purpose and a new bot pair creates a session in its place (once the server has room:
//! the old session closes after its abandon grace). What a soak needs to show that nothing grows with
//! players dropping, resuming and leaving.

use std::net::SocketAddr;

use bevy::prelude::*;
use heist_bots::ViveStyle;
use heist_shared::protocol::{Role, SeatTicket, TICK_HZ};

use super::pairs::{create_bot_pair_at, resumed_bot};

/// Game seconds a churning run may run ahead of the wall clock. Connect tokens are minted by the wall
/// clock, but a stepped server's netcode ages them by game time: a run more than the tokens' life (5
/// minutes) ahead would have every new connection refused as expired, so a long churning run is held to
/// real time once it is this far ahead.
pub const MAX_LEAD_S: f64 = 60.0;
/// Game seconds a dropped client stays away before it takes its seat back.
pub const AWAY_S: f64 = 5.0;
/// Game seconds between two tries to create a session in place of one its players left (the server may
/// still be full: the old session closes once its heist is abandoned).
const CREATE_RETRY_S: f64 = 1.0;
/// Game seconds leaving clients get to say so and be let go before they are dropped anyway.
const LEAVE_S: f64 = 2.0;

/// What the churn did over a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct ChurnCounts {
    /// Clients killed without a word (each comes back with its seat ticket).
    pub drops: u32,
    /// Seats taken back with a ticket.
    pub resumes: u32,
    /// Pairs that left on purpose.
    pub leaves: u32,
    /// Sessions created in place of those left.
    pub created: u32,
    /// Tries to create one refused (the server still full while the old session closes), each retried a
    /// second of game time later.
    pub create_retries: u32,
    /// Seats the server would not give back (the pair then leaves and a new one comes).
    pub resumes_refused: u32,
    /// Seats taken back as the server counted them (its `heist_resumes_total`).
    pub server_resumes: u64,
}

/// A session's bot pair (Vive's client, then Phantom's) and where it stands with the churn.
pub(super) struct Pair {
    /// The clients that are running (none while the pair is away or being replaced).
    pub apps: [Option<App>; 2],
    step: Step,
    /// Churn events so far (which one is next).
    events: u32,
}

enum Step {
    Playing,
    /// The client of `role` (0 Vive, 1 Phantom) is gone; it comes back at tick `back_at`.
    Away {
        role: usize,
        ticket: SeatTicket,
        back_at: u64,
    },
    /// Both clients leave; dropped at tick `until` at the latest.
    Leaving {
        until: u64,
    },
    /// Waiting to create a new session at tick `next_try`.
    Creating {
        next_try: u64,
    },
}

impl Pair {
    /// A pair whose clients are running.
    pub fn new(apps: [App; 2]) -> Self {
        let [vive, phantom] = apps;
        Self { apps: [Some(vive), Some(phantom)], step: Step::Playing, events: 0 }
    }

    /// The running clients.
    pub fn clients(&mut self) -> impl Iterator<Item = &mut App> {
        self.apps.iter_mut().flatten()
    }
}

/// Every session's churn: when each is due and what the server is reached at.
pub(super) struct Churn {
    /// Ticks between two events of a session.
    pub period: u64,
    /// The token endpoint.
    pub endpoint: SocketAddr,
    /// How the Vive bots play.
    pub style: ViveStyle,
    /// What happened so far.
    pub counts: ChurnCounts,
}

impl Churn {
    /// Advances pair `n` of `pairs` at tick `tick`: starts its event when due (the sessions' events are
    /// spread evenly over a period), and carries on one under way.
    pub fn step(&mut self, pair: &mut Pair, n: usize, pairs: usize, tick: u64) {
        pair.step = match std::mem::replace(&mut pair.step, Step::Playing) {
            Step::Playing => {
                let offset = self.period * n as u64 / pairs.max(1) as u64;
                let due = tick >= offset && (tick - offset).is_multiple_of(self.period) && tick > 0;
                if due { self.begin(pair, tick) } else { Step::Playing }
            }
            Step::Away { role, ticket, back_at } if tick >= back_at => self.come_back(pair, role, &ticket, tick),
            Step::Leaving { until } => {
                let gone = pair.apps.iter().all(|a| a.as_ref().is_none_or(|a| a.should_exit().is_some()));
                if gone || tick >= until {
                    pair.apps = [None, None];
                    self.counts.leaves += 1;
                    Step::Creating { next_try: tick }
                } else {
                    Step::Leaving { until }
                }
            }
            Step::Creating { next_try } if tick >= next_try => {
                match create_bot_pair_at(self.endpoint, self.style, u32::MAX, |_| {}) {
                    Ok(apps) => {
                        *pair = Pair { events: pair.events, ..Pair::new(apps) };
                        self.counts.created += 1;
                        Step::Playing
                    }
                    Err(_) => {
                        self.counts.create_retries += 1;
                        Step::Creating { next_try: tick + ticks(CREATE_RETRY_S) }
                    }
                }
            }
            step => step,
        };
    }

    /// The pair's next event: a client dies (Vive, then Phantom), or both leave.
    fn begin(&mut self, pair: &mut Pair, tick: u64) -> Step {
        let event = pair.events % 3;
        pair.events += 1;
        if event == 2 {
            return leave(pair, tick);
        }
        let role = event as usize;
        let ticket = pair.apps[role].as_ref().and_then(|a| a.world().get_resource::<heist_client::Inbox>()?.seat);
        let Some(ticket) = ticket else { return Step::Playing };
        pair.apps[role] = None; // killed: its socket closes, nobody says goodbye
        self.counts.drops += 1;
        Step::Away { role, ticket, back_at: tick + ticks(AWAY_S) }
    }

    /// A new client takes the seat of `role` back with its ticket; refused, the pair leaves.
    fn come_back(&mut self, pair: &mut Pair, role: usize, ticket: &SeatTicket, tick: u64) -> Step {
        let as_role = if role == 0 { Role::Vive } else { Role::Phantom };
        match resumed_bot(self.endpoint, as_role, ticket, self.style) {
            Ok(app) => {
                pair.apps[role] = Some(app);
                self.counts.resumes += 1;
                Step::Playing
            }
            Err(_) => {
                self.counts.resumes_refused += 1;
                leave(pair, tick)
            }
        }
    }
}

/// Both clients of `pair` leave on purpose (they say so and wait to be let go).
fn leave(pair: &mut Pair, tick: u64) -> Step {
    for app in pair.apps.iter_mut().flatten() {
        let now = app.world().resource::<Time<Real>>().elapsed_secs_f64();
        app.world_mut().resource_mut::<heist_client::Leaving>().start(now);
    }
    Step::Leaving { until: tick + ticks(LEAVE_S) }
}

/// Game seconds as ticks.
fn ticks(seconds: f64) -> u64 {
    (seconds * TICK_HZ).round() as u64
}
