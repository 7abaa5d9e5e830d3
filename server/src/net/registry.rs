//! The sessions a server hosts, as the token endpoint and the game loop share them: each session's id
//! (written into its players' tokens), room (the public first group of its join code), code book and
//! seats.
//!
//! The endpoint opens a session when a player asks to create one (within `--max-sessions` and a per
//! address rate); the game loop takes each opened session ([`Registry::take_opened`]) and spawns its
//! game, and closes it in the registry once the session is over, so its room, code and seats stop
//! working at once.

use std::collections::HashMap;
use std::net::IpAddr;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use heist_shared::protocol::join::JoinRefusal;
use heist_shared::protocol::{Role, SeatTicket};
use heist_transport::limit::{KeyedLimiter, Rate, address_key};

use super::codes::{CodeBook, new_room};
use super::seats::{Seat, Seats};

/// How fast sessions may be created.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CreateLimits {
    /// Per address (IPv6: per /64); default 10 at once, one every 6 s after.
    pub each: Rate,
    /// For the whole server; default 100 at once, 10 a second after.
    pub all: Rate,
}

impl Default for CreateLimits {
    fn default() -> Self {
        Self { each: Rate::new(1.0 / 6.0, 10.0), all: Rate::new(10.0, 100.0) }
    }
}

/// One hosted session, as the endpoint sees it (cheap to clone: the code book and seats are shared).
#[derive(Clone, Debug)]
pub struct SessionEntry {
    /// Its id, in every token of its players (never shown: the log uses its own).
    pub id: u64,
    /// Its room, the first group of its code.
    pub room: String,
    /// Its join code.
    pub codes: CodeBook,
    /// Its seats.
    pub seats: Seats,
    /// The shard that plays it: the replication server, on a game port of its own, its players connect to.
    pub shard: usize,
}

struct Inner {
    sessions: HashMap<u64, SessionEntry>,
    rooms: HashMap<String, u64>,
    /// Open sessions per shard.
    load: Vec<usize>,
    opened: Vec<u64>,
    creates: KeyedLimiter<IpAddr>,
    draining: bool,
}

/// Every session of the server (cheap to clone).
#[derive(Clone)]
pub struct Registry {
    inner: Arc<Mutex<Inner>>,
    max: usize,
    shard_size: usize,
    code_ttl: Duration,
    started: Instant,
}

impl std::fmt::Debug for Registry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Registry({} of {} sessions)", self.len(), self.max)
    }
}

impl Registry {
    /// No session yet; at most `max` at once, codes valid for `code_ttl`; one shard.
    pub fn new(max: usize, code_ttl: Duration, limits: CreateLimits) -> Self {
        Self::sharded(max, max, code_ttl, limits)
    }

    /// No session yet; at most `max` at once, at most `shard_size` in each of
    /// `max.div_ceil(shard_size)` shards; codes valid for `code_ttl`.
    pub fn sharded(max: usize, shard_size: usize, code_ttl: Duration, limits: CreateLimits) -> Self {
        let shard_size = shard_size.clamp(1, max.max(1));
        let inner = Inner {
            sessions: HashMap::new(),
            rooms: HashMap::new(),
            load: vec![0; max.max(1).div_ceil(shard_size)],
            opened: Vec::new(),
            draining: false,
            creates: KeyedLimiter::new(limits.each, limits.all, 16_384),
        };
        Self { inner: Arc::new(Mutex::new(inner)), max, shard_size, code_ttl, started: Instant::now() }
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Sessions open now.
    pub fn len(&self) -> usize {
        self.lock().sessions.len()
    }

    /// True when no session is open.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The most sessions open at once.
    pub fn max(&self) -> usize {
        self.max
    }

    /// The shards sessions are spread over.
    pub fn shards(&self) -> usize {
        self.lock().load.len()
    }

    /// The most sessions one shard plays at once.
    pub fn shard_size(&self) -> usize {
        self.shard_size
    }

    /// Opens a session asked for from `from` (`None`: the host's own, never rate limited): a fresh id,
    /// room, code and free seats. The game loop spawns its game ([`Registry::take_opened`]).
    pub fn open(&self, from: Option<IpAddr>) -> Result<SessionEntry, JoinRefusal> {
        let mut inner = self.lock();
        if inner.draining {
            return Err(JoinRefusal::Draining);
        }
        if inner.sessions.len() >= self.max {
            return Err(JoinRefusal::Full { max: self.max as u32 });
        }
        if let Some(ip) = from {
            let now = self.started.elapsed().as_secs_f64();
            if !inner.creates.take(address_key(ip), now) {
                return Err(JoinRefusal::TooManySessions { retry_after_s: 6 });
            }
        }
        let room = loop {
            let room = new_room();
            if !inner.rooms.contains_key(&room) {
                break room;
            }
        };
        let id = loop {
            let id: u64 = rand::random();
            if id != 0 && !inner.sessions.contains_key(&id) {
                break id;
            }
        };
        // The least busy shard (the first of equals): sessions spread evenly, so each shard's
        // replication walks as few of them as it can.
        let (shard, _) = inner.load.iter().enumerate().min_by_key(|(i, n)| (**n, *i)).unwrap_or((0, &0));
        let entry = SessionEntry {
            id,
            room: room.clone(),
            codes: CodeBook::new(&room, self.code_ttl),
            seats: Seats::default(),
            shard,
        };
        inner.load[shard] += 1;
        inner.rooms.insert(room, id);
        inner.sessions.insert(id, entry.clone());
        inner.opened.push(id);
        Ok(entry)
    }

    /// The server is shutting down: from now on every request for a new session is refused
    /// ([`JoinRefusal::Draining`]); joins and resumes of open sessions still work.
    pub fn stop_opening(&self) {
        self.lock().draining = true;
    }

    /// True once [`Registry::stop_opening`] was called.
    pub fn is_draining(&self) -> bool {
        self.lock().draining
    }

    /// The public ids of the seats of every open session that a player holds or that are kept for one
    /// who dropped, as hex (what an orchestrator lists as the server's players).
    pub fn seated_players(&self) -> Vec<String> {
        let inner = self.lock();
        let mut ids = Vec::with_capacity(inner.sessions.len() * 2);
        for entry in inner.sessions.values() {
            for role in [Role::Vive, Role::Phantom] {
                if let Seat::Taken(ticket) | Seat::Kept { ticket, .. } = entry.seats.get(role) {
                    ids.push(ticket.public_id().iter().map(|b| format!("{b:02x}")).collect());
                }
            }
        }
        ids.sort_unstable();
        ids
    }

    /// The sessions of `shard` opened since the last call, for its game loop to spawn.
    pub fn take_opened(&self, shard: usize) -> Vec<SessionEntry> {
        let mut inner = self.lock();
        if inner.opened.is_empty() {
            return Vec::new();
        }
        let Inner { opened, sessions, .. } = &mut *inner;
        let mut taken = Vec::new();
        opened.retain(|id| match sessions.get(id) {
            Some(entry) if entry.shard == shard => {
                taken.push(entry.clone());
                false
            }
            Some(_) => true,
            None => false,
        });
        taken
    }

    /// The session whose room is `room`.
    pub fn by_room(&self, room: &str) -> Option<SessionEntry> {
        let inner = self.lock();
        inner.rooms.get(room).and_then(|id| inner.sessions.get(id)).cloned()
    }

    /// The session with id `id`.
    pub fn get(&self, id: u64) -> Option<SessionEntry> {
        self.lock().sessions.get(&id).cloned()
    }

    /// The session whose `role` seat (taken or kept) has the ticket named by `seat`
    /// ([`SeatTicket::public_id`]), and that ticket.
    pub fn by_seat(&self, role: Role, seat: &[u8; 16]) -> Result<(SessionEntry, SeatTicket), JoinRefusal> {
        let inner = self.lock();
        inner
            .sessions
            .values()
            .find_map(|entry| match entry.seats.get(role) {
                Seat::Taken(t) | Seat::Kept { ticket: t, .. } if t.public_id() == *seat => Some((entry.clone(), t)),
                _ => None,
            })
            .ok_or(JoinRefusal::NoSeat(role))
    }

    /// Closes session `id`: its room, code and seats stop working.
    pub fn close(&self, id: u64) {
        let mut inner = self.lock();
        if let Some(entry) = inner.sessions.remove(&id) {
            inner.rooms.remove(&entry.room);
            if let Some(n) = inner.load.get_mut(entry.shard) {
                *n = n.saturating_sub(1);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn registry(max: usize) -> Registry {
        Registry::new(max, Duration::from_secs(60), CreateLimits::default())
    }

    #[test]
    fn a_draining_registry_opens_no_session_but_keeps_the_open_ones_and_lists_their_seated_players() {
        let r = registry(8);
        let a = r.open(None).unwrap();
        let (vive, phantom) = (SeatTicket::random(), SeatTicket::random());
        a.seats.set(Role::Vive, Seat::Taken(vive));
        a.seats.set(Role::Phantom, Seat::Kept { ticket: phantom, since: Instant::now() });
        let hex = |t: SeatTicket| t.public_id().iter().map(|b| format!("{b:02x}")).collect::<String>();
        let mut want = vec![hex(vive), hex(phantom)];
        want.sort();
        assert_eq!(r.seated_players(), want, "taken and kept seats are players; free ones are not");
        r.stop_opening();
        assert!(r.is_draining());
        assert_eq!(r.open(Some("127.0.0.1".parse().unwrap())).map(|e| e.id), Err(JoinRefusal::Draining));
        assert_eq!(r.open(None).map(|e| e.id), Err(JoinRefusal::Draining));
        assert_eq!(r.by_room(&a.room).map(|e| e.id), Some(a.id), "an open session still takes its partner");
        r.close(a.id);
        assert!(r.seated_players().is_empty());
    }

    #[test]
    fn sessions_have_their_own_room_code_and_seats_and_closing_one_frees_its_room() {
        let r = registry(8);
        let (a, b) = (r.open(None).unwrap(), r.open(None).unwrap());
        assert_ne!((a.id, &a.room), (b.id, &b.room));
        assert!(a.codes.current().code.starts_with(&a.room), "{}", a.codes.current().code);
        assert_eq!(r.take_opened(0).iter().map(|e| e.id).collect::<Vec<_>>(), [a.id, b.id]);
        assert!(r.take_opened(0).is_empty());
        let ticket = SeatTicket::random();
        a.seats.set(Role::Vive, Seat::Taken(ticket));
        assert_eq!(r.by_seat(Role::Vive, &ticket.public_id()).map(|(e, t)| (e.id, t)), Ok((a.id, ticket)));
        assert!(r.by_seat(Role::Phantom, &ticket.public_id()).is_err(), "a seat is one role's");
        assert_eq!(b.seats.get(Role::Vive), Seat::Free, "the other session's seat is its own");
        r.close(a.id);
        assert!(r.by_room(&a.room).is_none() && r.get(a.id).is_none());
        assert_eq!(r.by_seat(Role::Vive, &ticket.public_id()).map(|(e, _)| e.id), Err(JoinRefusal::NoSeat(Role::Vive)));
        assert_eq!(r.by_room(&b.room).map(|e| e.id), Some(b.id));
    }

    #[test]
    fn sessions_spread_over_the_shards_evenly_and_a_closed_one_frees_its_shards_place() {
        let r = Registry::sharded(7, 3, Duration::from_secs(60), CreateLimits::default());
        assert_eq!(r.shards(), 3, "7 sessions of at most 3 a shard need 3 shards");
        let opened: Vec<SessionEntry> = (0..6).map(|_| r.open(None).unwrap()).collect();
        assert_eq!(opened.iter().map(|e| e.shard).collect::<Vec<_>>(), [0, 1, 2, 0, 1, 2]);
        assert_eq!(r.take_opened(1).iter().map(|e| e.id).collect::<Vec<_>>(), [opened[1].id, opened[4].id]);
        assert!(r.take_opened(1).is_empty(), "taken once");
        assert_eq!(r.take_opened(0).len(), 2, "shard 0's are still there for it");
        r.close(opened[4].id);
        assert_eq!(r.open(None).unwrap().shard, 1, "the freed place is the least busy");
        assert_eq!(r.open(None).unwrap().shard, 0);
        assert_eq!(r.open(None).map(|e| e.id), Err(JoinRefusal::Full { max: 7 }), "the whole server's limit holds");
        assert_eq!(Registry::sharded(5, 0, Duration::from_secs(60), CreateLimits::default()).shards(), 5);
    }

    #[test]
    fn a_full_server_and_a_fast_creator_are_refused() {
        let r = registry(2);
        let ip: IpAddr = "192.0.2.7".parse().unwrap();
        r.open(Some(ip)).unwrap();
        r.open(Some(ip)).unwrap();
        assert_eq!(r.open(Some(ip)).map(|e| e.id), Err(JoinRefusal::Full { max: 2 }));
        let r = registry(100);
        let made = (0..20).filter(|_| r.open(Some(ip)).is_ok()).count();
        assert_eq!(made, 10, "an address creates its burst, then waits");
        assert!(r.open(Some("192.0.2.8".parse().unwrap())).is_ok(), "another address is not held back");
        assert!(r.open(None).is_ok(), "the host's own session is never rate limited");
    }
}
