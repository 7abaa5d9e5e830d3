//! Coming back by itself: when the link to the server is lost (3 s of silence, or netcode gave up) and
//! nobody said why, the client asks the token endpoint to take its seat back — the resume exchange with
//! the seat ticket of its welcome — on a worker thread, with back-off, for [`REJOIN_FOR_S`] (the server
//! keeps the seat that long); then it gives up, saying why. A new token replaces the transport: the
//! replicated entities of the old connection are despawned (the new one receives the whole world again),
//! and the server's catch-up (briefings, the bench copy, Vive's fresh move numbering) follows the welcome.

use std::net::SocketAddr;
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::Duration;

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use bevy_replicon_renet::RenetClient;
use heist_shared::protocol::join::JoinRefusal;
use heist_shared::protocol::{Role, SeatTicket};
use heist_transport::renetcode::ConnectToken;

use crate::{Inbox, JoinError, Leaving, Link};

/// Seconds a client keeps trying to take its seat back (the server's hold, `rules::SEAT_HOLD_S`).
pub const REJOIN_FOR_S: f64 = heist_shared::rules::SEAT_HOLD_S as f64;
/// Seconds before the first attempt; each failed attempt doubles the wait, up to [`MAX_RETRY_S`].
pub const FIRST_RETRY_S: f64 = 0.5;
/// The longest wait between attempts, seconds.
pub const MAX_RETRY_S: f64 = 8.0;
/// How long one attempt may take, seconds.
const ATTEMPT_TIMEOUT: Duration = Duration::from_secs(3);

/// Where the client stands with coming back, for the apps to tell the player.
#[derive(Resource, Clone, Debug, Default, PartialEq, Eq)]
pub enum Reconnect {
    /// Connected, or never tried.
    #[default]
    Steady,
    /// The link was lost; trying to take the seat back (`attempts` made so far).
    Trying {
        /// Attempts made.
        attempts: u32,
    },
    /// Could not come back; why, for the player. The session is over for this client.
    GaveUp(String),
}

impl Reconnect {
    /// True while trying to come back.
    pub fn is_trying(&self) -> bool {
        matches!(self, Reconnect::Trying { .. })
    }
}

/// Makes the client take its seat back by itself after a lost connection (insert it after connecting;
/// [`crate::hold_seat`] does).
#[derive(Resource, Debug)]
pub struct Rejoin {
    endpoint: SocketAddr,
    role: Role,
    give_up_after_s: f64,
    step: Step,
}

#[derive(Debug)]
enum Step {
    /// Nothing to do.
    Idle,
    /// Lost at `since`; the next attempt at `next_at`, waiting `delay` after a failure.
    Waiting { since: f64, next_at: f64, delay: f64 },
    /// An attempt runs on its thread (the mutex only makes the receiver shareable, as a resource must be).
    Asking { since: f64, delay: f64, answer: Mutex<Receiver<Answer>> },
    /// The old transport is gone; the new one goes in next frame.
    Swapping { since: f64, token: Box<ConnectToken>, welcomes: u32 },
    /// The new transport is in; waiting for its welcome.
    Welcoming { since: f64, welcomes: u32 },
    /// Gave up.
    Done,
}

impl Rejoin {
    /// Rejoins at `endpoint` (the token endpoint) as `role`.
    pub fn new(endpoint: SocketAddr, role: Role) -> Self {
        Self { endpoint, role, give_up_after_s: REJOIN_FOR_S, step: Step::Idle }
    }

    /// Gives up after `seconds` instead of [`REJOIN_FOR_S`] (a server known to keep seats for less).
    pub fn giving_up_after(mut self, seconds: f64) -> Self {
        self.give_up_after_s = seconds;
        self
    }
}

/// True when the link is lost for no reason the server or the player gave.
fn lost(link: Link, inbox: &Inbox, leaving: &Leaving) -> bool {
    matches!(link, Link::Silent | Link::Gone) && inbox.disconnect.is_none() && leaving.since.is_none()
}

/// Drives [`Rejoin`]: notices the loss, runs the attempts with back-off, swaps the transport.
#[allow(clippy::too_many_arguments)]
pub(crate) fn drive(
    mut commands: Commands,
    rejoin: Option<ResMut<Rejoin>>,
    mut reconnect: ResMut<Reconnect>,
    link: Res<Link>,
    inbox: Res<Inbox>,
    leaving: Res<Leaving>,
    channels: Res<RepliconChannels>,
    remote: Query<Entity, With<Remote>>,
    time: Res<Time<Real>>,
) {
    let Some(mut rejoin) = rejoin else { return };
    let now = time.elapsed_secs_f64();
    let (endpoint, role, window) = (rejoin.endpoint, rejoin.role, rejoin.give_up_after_s);
    let give_up = |reconnect: &mut Reconnect, why: String| {
        warn!("giving up on the session: {why}");
        *reconnect = Reconnect::GaveUp(why);
        Step::Done
    };
    let step = std::mem::replace(&mut rejoin.step, Step::Done);
    let told = inbox.disconnect.is_some() || leaving.since.is_some();
    rejoin.step = match step {
        // The server said why (to the new connection), or the player leaves: nothing to come back to.
        Step::Waiting { .. } | Step::Asking { .. } | Step::Swapping { .. } | Step::Welcoming { .. } if told => {
            *reconnect = Reconnect::Steady;
            Step::Done
        }
        Step::Idle if lost(*link, &inbox, &leaving) && inbox.seat.is_some() => {
            info!("the link to the server is lost: trying to take the {role} seat back");
            *reconnect = Reconnect::Trying { attempts: 0 };
            Step::Waiting { since: now, next_at: now + FIRST_RETRY_S, delay: FIRST_RETRY_S }
        }
        Step::Idle => Step::Idle,
        Step::Waiting { .. } | Step::Asking { .. } if *link == Link::Up => {
            info!("the old connection came back by itself");
            *reconnect = Reconnect::Steady;
            Step::Idle
        }
        Step::Waiting { since, .. } | Step::Asking { since, .. } if now - since >= window => {
            give_up(&mut reconnect, format!("no way back into the session for {window:.0} s"))
        }
        Step::Waiting { since, next_at, delay } if now >= next_at => match inbox.seat {
            Some(ticket) => {
                let attempts = match *reconnect {
                    Reconnect::Trying { attempts } => attempts + 1,
                    _ => 1,
                };
                *reconnect = Reconnect::Trying { attempts };
                Step::Asking { since, delay, answer: ask(endpoint, role, ticket) }
            }
            None => give_up(&mut reconnect, "no seat ticket to come back with".into()),
        },
        waiting @ Step::Waiting { .. } => waiting,
        Step::Asking { since, delay, answer } => {
            match answer.lock().map_or(Err(TryRecvError::Disconnected), |a| a.try_recv()) {
                Err(TryRecvError::Empty) => Step::Asking { since, delay, answer },
                Ok(Ok(token)) => {
                    for e in &remote {
                        commands.entity(e).despawn();
                    }
                    commands.remove_resource::<RenetClient>();
                    commands.remove_resource::<crate::transport::ClientTransport>();
                    Step::Swapping { since, token: Box::new(token), welcomes: inbox.received.welcome }
                }
                Ok(Err(JoinError::Refused(
                    refusal @ (JoinRefusal::NoSeat(_) | JoinRefusal::WrongTicket | JoinRefusal::Version { .. }),
                ))) => give_up(&mut reconnect, refusal.to_string()),
                Ok(Err(e)) => {
                    info!("could not take the seat back yet: {e}");
                    let delay = (delay * 2.0).min(MAX_RETRY_S);
                    Step::Waiting { since, next_at: now + delay, delay }
                }
                Err(TryRecvError::Disconnected) => {
                    let delay = (delay * 2.0).min(MAX_RETRY_S);
                    Step::Waiting { since, next_at: now + delay, delay }
                }
            }
        }
        Step::Swapping { since, token, welcomes } => match crate::transport::open_with_token(*token, &channels) {
            Ok((renet, transport)) => {
                commands.insert_resource(renet);
                commands.insert_resource(transport);
                Step::Welcoming { since, welcomes }
            }
            Err(e) => give_up(&mut reconnect, format!("cannot connect again: {e}")),
        },
        Step::Welcoming { welcomes, .. } if inbox.received.welcome > welcomes => {
            info!("took the {role} seat back");
            *reconnect = Reconnect::Steady;
            Step::Idle
        }
        Step::Welcoming { since, .. } if now - since >= window => {
            give_up(&mut reconnect, format!("no way back into the session for {window:.0} s"))
        }
        Step::Welcoming { since, .. } if *link == Link::Gone => {
            // The new connection failed too: try again within the same minute.
            Step::Waiting { since, next_at: now + FIRST_RETRY_S, delay: FIRST_RETRY_S }
        }
        welcoming @ Step::Welcoming { .. } => welcoming,
        Step::Done => Step::Done,
    };
}

/// What an attempt brings back.
type Answer = Result<ConnectToken, JoinError>;

/// One attempt on its own thread (the exchange blocks for up to [`ATTEMPT_TIMEOUT`] per step).
fn ask(endpoint: SocketAddr, role: Role, ticket: SeatTicket) -> Mutex<Receiver<Answer>> {
    let (tx, rx) = std::sync::mpsc::channel();
    let spawned = std::thread::Builder::new().name("rejoin".into()).spawn(move || {
        let _ = tx.send(crate::token::request_resume_token(endpoint, role, &ticket, ATTEMPT_TIMEOUT));
    });
    if let Err(e) = spawned {
        warn!("cannot start a rejoin attempt: {e}");
    }
    Mutex::new(rx)
}
