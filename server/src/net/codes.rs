//! Join codes: a session's room (the public first group, like `K7QX`) and the secret rest, rotated by
//! the host; the book a session keeps its current code in.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, SystemTime};

/// A join code and when it stops working.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct JoinCode {
    /// The code, like `K7QX-2M4P-R9TC`.
    pub code: String,
    /// When it expires (wall clock).
    pub expires_at: SystemTime,
}

impl JoinCode {
    /// True once it has expired.
    pub fn is_expired(&self) -> bool {
        SystemTime::now() >= self.expires_at
    }

    /// "K7QX-2M4P-R9TC (expires 09:54:26 UTC, in 30 min)", for the host's terminal.
    pub fn describe(&self) -> String {
        let left = self.expires_at.duration_since(SystemTime::now()).unwrap_or_default();
        let at = self.expires_at.duration_since(SystemTime::UNIX_EPOCH).unwrap_or_default().as_secs() % 86_400;
        format!(
            "{} (expires {:02}:{:02}:{:02} UTC, in {} min)",
            self.code,
            at / 3600,
            at / 60 % 60,
            at % 60,
            left.as_secs().div_ceil(60)
        )
    }
}

/// A session's current join code, shared by the endpoint and the host, who can replace it. Every code
/// of the book starts with the session's room.
#[derive(Clone, Debug)]
pub struct CodeBook {
    current: Arc<Mutex<JoinCode>>,
    room: String,
    ttl: Duration,
}

impl CodeBook {
    /// A fresh code in `room` valid for `ttl`.
    pub fn new(room: &str, ttl: Duration) -> Self {
        Self { current: Arc::new(Mutex::new(Self::fresh(room, ttl))), room: room.to_owned(), ttl }
    }

    fn fresh(room: &str, ttl: Duration) -> JoinCode {
        JoinCode { code: format!("{room}-{}", new_secret()), expires_at: SystemTime::now() + ttl }
    }

    fn lock(&self) -> MutexGuard<'_, JoinCode> {
        self.current.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The code in force.
    pub fn current(&self) -> JoinCode {
        self.lock().clone()
    }

    /// Replaces the code with a fresh one (the old one stops working at once).
    pub fn rotate(&self) -> JoinCode {
        let fresh = Self::fresh(&self.room, self.ttl);
        *self.lock() = fresh.clone();
        fresh
    }
}

/// Letters of join codes: no 0/O, 1/I to mix up.
const ALPHABET: &[u8] = b"ABCDEFGHJKLMNPQRSTUVWXYZ23456789";

fn letters(n: usize) -> impl Iterator<Item = char> {
    (0..n).map(|_| ALPHABET[rand::random_range(0..ALPHABET.len())] as char)
}

/// A fresh room: the public first group of a session's codes, like `K7QX` (20 bits; unique among the
/// open sessions).
pub fn new_room() -> String {
    letters(4).collect()
}

/// The secret part of a join code, like `2M4P-R9TC` (40 bits: 32⁸).
fn new_secret() -> String {
    let mut s: String = letters(4).collect();
    s.push('-');
    s.extend(letters(4));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn join_codes_look_right() {
        let c = CodeBook::new("K7QX", Duration::from_secs(60)).current().code;
        assert_eq!(c.len(), 14, "{c}");
        assert!(c.starts_with("K7QX-") && &c[9..10] == "-", "{c}");
        assert_eq!(heist_shared::protocol::join::room_of(&c).as_deref(), Ok("K7QX"));
    }

    #[test]
    fn a_rotated_code_replaces_the_old_one_and_expires_later() {
        let book = CodeBook::new("ROOM", Duration::from_secs(60));
        let first = book.current();
        assert!(!first.is_expired());
        assert!(first.describe().contains("in 1 min"), "{}", first.describe());
        let second = book.rotate();
        assert_ne!(second.code, first.code);
        assert_eq!(book.current(), second);
        assert!(second.code.starts_with("ROOM-"), "a rotated code stays in its room");
        assert!(CodeBook::new("ROOM", Duration::ZERO).current().is_expired());
    }
}
