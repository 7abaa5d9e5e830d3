//! A session's two seats (Vive's, Phantom's), their tickets and the clients in them ([`Roles`]), shared by the game loop, which admits
//! and lets go, and the token endpoint, which decides who may get a token for which seat.
//!
//! A seat is free, taken by a connected player, or kept for the player who dropped from it: then only
//! the holder of its ticket (the resume exchange) can take it back, for [`rules::SEAT_HOLD_S`] at most.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use bevy::prelude::Entity;
use heist_shared::protocol::join::JoinRefusal;
use heist_shared::protocol::{Role, SeatTicket};
use heist_shared::rules;

/// One seat.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Seat {
    /// Nobody plays the role: anyone with the join code may take it.
    #[default]
    Free,
    /// A connected player holds it.
    Taken(SeatTicket),
    /// Its player dropped; kept for the holder of the ticket since `since`.
    Kept {
        /// The seat's ticket.
        ticket: SeatTicket,
        /// When the player dropped.
        since: Instant,
    },
}

/// Both seats, shared (cheap to clone).
#[derive(Clone, Debug, Default)]
pub struct Seats(Arc<Mutex<[Seat; 2]>>);

impl Seats {
    fn lock(&self) -> MutexGuard<'_, [Seat; 2]> {
        self.0.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn index(role: Role) -> usize {
        usize::from(role.to_byte() - 1)
    }

    /// `role`'s seat now.
    pub fn get(&self, role: Role) -> Seat {
        self.lock()[Self::index(role)]
    }

    /// Sets `role`'s seat.
    pub fn set(&self, role: Role, seat: Seat) {
        self.lock()[Self::index(role)] = seat;
    }

    /// Whether a player with the join code may have a token for `role` (the endpoint asks).
    pub fn check_join(&self, role: Role) -> Result<(), JoinRefusal> {
        match self.get(role) {
            Seat::Free => Ok(()),
            Seat::Taken(_) => Err(JoinRefusal::RoleTaken(role)),
            Seat::Kept { since, .. } => {
                let left = (f64::from(rules::SEAT_HOLD_S) - since.elapsed().as_secs_f64()).max(1.0);
                Err(JoinRefusal::SeatHeld { role, for_s: left.ceil() as u32 })
            }
        }
    }

    /// The ticket a resume of `role` must prove it holds: the seat's, whether kept or still taken (a
    /// restarted client comes back before the server noticed its old connection is dead).
    pub fn ticket_to_resume(&self, role: Role) -> Result<SeatTicket, JoinRefusal> {
        match self.get(role) {
            Seat::Free => Err(JoinRefusal::NoSeat(role)),
            Seat::Taken(ticket) | Seat::Kept { ticket, .. } => Ok(ticket),
        }
    }
}

/// Which client entity plays which role in a session.
#[derive(Default, Debug)]
pub struct Roles {
    /// Vive's client.
    pub vive: Option<Entity>,
    /// Phantom's client.
    pub phantom: Option<Entity>,
}

impl Roles {
    /// The client playing `role`.
    pub fn get(&self, role: Role) -> Option<Entity> {
        match role {
            Role::Vive => self.vive,
            Role::Phantom => self.phantom,
        }
    }

    pub(super) fn slot(&mut self, role: Role) -> &mut Option<Entity> {
        match role {
            Role::Vive => &mut self.vive,
            Role::Phantom => &mut self.phantom,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_kept_seat_is_refused_to_the_code_and_open_to_its_ticket() {
        let seats = Seats::default();
        assert_eq!(seats.check_join(Role::Vive), Ok(()));
        assert_eq!(seats.ticket_to_resume(Role::Vive), Err(JoinRefusal::NoSeat(Role::Vive)));
        let ticket = SeatTicket::random();
        seats.set(Role::Vive, Seat::Taken(ticket));
        assert_eq!(seats.check_join(Role::Vive), Err(JoinRefusal::RoleTaken(Role::Vive)));
        assert_eq!(seats.ticket_to_resume(Role::Vive), Ok(ticket));
        seats.set(Role::Vive, Seat::Kept { ticket, since: Instant::now() });
        assert!(matches!(
            seats.check_join(Role::Vive),
            Err(JoinRefusal::SeatHeld { role: Role::Vive, for_s: 59..=60 })
        ));
        assert_eq!(seats.ticket_to_resume(Role::Vive), Ok(ticket));
        assert_eq!(seats.check_join(Role::Phantom), Ok(()), "the other seat is its own");
    }
}
