//! The join exchange: a player proves they know the join code and receives a netcode connect token,
//! without the code, the token or its session keys ever crossing the wire in clear.
//!
//! A SPAKE2 exchange keyed by the join code (as magic-wormhole does with its short codes) gives both sides
//! one shared key only when both used the same code; a passive observer learns nothing, and an active
//! one gets one guess per attempt (the server limits attempts). Over TCP, each message is one frame: a
//! big-endian `u16` length and a postcard body.
//!
//! ```text
//! client                                   server
//!   Hello { version, room, role, pake_a } ──▶
//!                                     ◀──  Challenge { pake_b }
//!   Confirm { mac(K, transcript) }    ──▶  (a wrong mac is a wrong code)
//!                                     ◀──  Token { sealed(K, connect token) }
//! ```
//!
//! A player coming back to a held seat opens with `Resume` instead of `Hello`: the same exchange, keyed by
//! the seat ticket the server gave them at their first admission instead of the join code (so it works
//! after the code expired or was rotated, and only for that seat's holder). The token it yields carries the
//! ticket, which admission checks again; it names the seat by the ticket's public id
//! ([`SeatTicket::public_id`]), which says which session it is in without giving the ticket away.
//!
//! One server hosts many sessions. A join code is `ROOM-XXXX-XXXX`: the first group names the session
//! (its *room*, sent in clear in the hello so the server knows which code to key the exchange with), the
//! whole code is the secret (the last two groups, 40 bits, are never sent). A player *creates* a session
//! with `Create`: the same exchange keyed by a fixed password (so the channel is encrypted against a
//! passive observer; anyone may create, within the server's limits), ending in `Created` with the new
//! session's code and the creator's token, sealed together ([`NewSession`]).

use serde::{Deserialize, Serialize};
use spake2::{Ed25519Group, Identity, Password, Spake2};

use super::ids::Role;
use super::token::SeatTicket;

/// Version of the join exchange; both sides must speak the same.
pub const JOIN_VERSION: u8 = 5;
/// Largest frame body either side accepts, bytes (a sealed token is ~2.1 KB).
pub const MAX_FRAME: usize = 4096;

/// What a client sends.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum JoinMsg {
    /// Opens the exchange.
    Hello {
        /// [`JOIN_VERSION`] of the client.
        version: u8,
        /// The session's room: the code's first group ([`room_of`]).
        room: String,
        /// The role the player wants.
        role: Role,
        /// The client's SPAKE2 message.
        pake: Vec<u8>,
    },
    /// Proves the client derived the same key (that it knows the code).
    Confirm {
        /// Keyed hash of the transcript.
        mac: [u8; 32],
    },
    /// Opens the exchange of a player taking back a held seat: the SPAKE2 message is keyed by the seat
    /// ticket ([`Pake::client_ticket`]).
    Resume {
        /// [`JOIN_VERSION`] of the client.
        version: u8,
        /// The seat's role.
        role: Role,
        /// The seat's public id ([`SeatTicket::public_id`]): which session's seat.
        seat: [u8; 16],
        /// The client's SPAKE2 message.
        pake: Vec<u8>,
    },
    /// Opens the exchange of a player creating a new session, in which they will play `role`: the
    /// SPAKE2 message is keyed by a fixed password ([`Pake::client_create`]).
    Create {
        /// [`JOIN_VERSION`] of the client.
        version: u8,
        /// The role the creator plays.
        role: Role,
        /// The client's SPAKE2 message.
        pake: Vec<u8>,
    },
}

/// What a `Created` reply seals: the new session's join code (to give the partner) and the creator's
/// connect token.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct NewSession {
    /// The join code, like `K7QX-2M4P-R9TC`.
    pub code: String,
    /// The creator's connect token (netcode wire format).
    pub token: Vec<u8>,
}

/// What the server answers.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum JoinReply {
    /// The server's SPAKE2 message.
    Challenge {
        /// SPAKE2 message.
        pake: Vec<u8>,
    },
    /// The connect token (netcode wire format), sealed with the exchange's key.
    Token {
        /// ChaCha20-Poly1305 ciphertext and tag.
        sealed: Vec<u8>,
    },
    /// A session was created: [`NewSession`] (postcard), sealed with the exchange's key.
    Created {
        /// ChaCha20-Poly1305 ciphertext and tag.
        sealed: Vec<u8>,
    },
    /// Turned away, with the reason.
    Refused(JoinRefusal),
}

/// Why the server will not give a token. Sent as data, readable (and speakable) by the client.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, thiserror::Error)]
pub enum JoinRefusal {
    /// The code the player typed is not the host's.
    #[error("wrong join code")]
    WrongCode,
    /// The host's code has expired; the host must give a new one.
    #[error("the join code has expired; ask the host for a new one")]
    CodeExpired,
    /// Someone already plays that role.
    #[error("the {0} role is already taken")]
    RoleTaken(Role),
    /// The role's player dropped and their seat is kept for them (only their seat ticket takes it).
    #[error("the {role} seat is kept for its player, who dropped, for {for_s} s more")]
    SeatHeld {
        /// The seat.
        role: Role,
        /// Seconds the server keeps it at most.
        for_s: u32,
    },
    /// A resume named a seat that is not kept for anyone (the session ended, or it was given up).
    #[error("there is no {0} seat to come back to: join with the code")]
    NoSeat(Role),
    /// A resume's seat ticket is not the seat's.
    #[error("the seat ticket is not the one of that seat")]
    WrongTicket,
    /// Too many wrong codes came from this address.
    #[error("too many wrong join codes from your address; try again in {retry_after_s} s")]
    TooManyWrongCodes {
        /// Seconds until this address may try again.
        retry_after_s: u32,
    },
    /// The server is refusing attempts for a while (too many wrong codes from everywhere, or too many
    /// connections).
    #[error("the host is not taking join attempts right now; try again in {retry_after_s} s")]
    Busy {
        /// Seconds to wait.
        retry_after_s: u32,
    },
    /// The client speaks another version of the exchange.
    #[error("the host speaks join version {server}, this client {client}: update one of them")]
    Version {
        /// The server's version.
        server: u8,
        /// The client's version.
        client: u8,
    },
    /// The server hosts as many sessions as it may.
    #[error("the server hosts {max} sessions already, its most; try another server or later")]
    Full {
        /// The server's `--max-sessions`.
        max: u32,
    },
    /// This address created sessions too fast.
    #[error("too many new sessions from your address; try again in {retry_after_s} s")]
    TooManySessions {
        /// Seconds until this address may create another.
        retry_after_s: u32,
    },
    /// The request was not understood.
    #[error("bad join request: {0}")]
    BadRequest(String),
    /// The server could not make a token.
    #[error("the host could not make a token: {0}")]
    Internal(String),
    /// The server is shutting down: it lets its running heists finish and creates no new session.
    #[error("the server is shutting down and creates no new session; try another server or later")]
    Draining,
}

impl JoinRefusal {
    /// A short name of the kind of refusal, for metrics and logs (`wrong_code`, `full`, …).
    pub fn kind(&self) -> &'static str {
        match self {
            JoinRefusal::WrongCode => "wrong_code",
            JoinRefusal::CodeExpired => "code_expired",
            JoinRefusal::RoleTaken(_) => "role_taken",
            JoinRefusal::SeatHeld { .. } => "seat_held",
            JoinRefusal::NoSeat(_) => "no_seat",
            JoinRefusal::WrongTicket => "wrong_ticket",
            JoinRefusal::TooManyWrongCodes { .. } => "too_many_wrong_codes",
            JoinRefusal::Busy { .. } => "busy",
            JoinRefusal::Version { .. } => "version",
            JoinRefusal::Full { .. } => "full",
            JoinRefusal::TooManySessions { .. } => "too_many_sessions",
            JoinRefusal::BadRequest(_) => "bad_request",
            JoinRefusal::Internal(_) => "internal",
            JoinRefusal::Draining => "draining",
        }
    }
}

/// Encodes `msg` as one frame.
pub fn frame<T: Serialize>(msg: &T) -> Vec<u8> {
    let body = postcard::to_allocvec(msg).unwrap_or_default();
    let mut out = Vec::with_capacity(2 + body.len());
    out.extend_from_slice(&(body.len() as u16).to_be_bytes());
    out.extend_from_slice(&body);
    out
}

/// The body length a frame header announces, or why it is refused.
pub fn frame_len(header: [u8; 2], max: usize) -> Result<usize, String> {
    let len = usize::from(u16::from_be_bytes(header));
    if len == 0 || len > max { Err(format!("frame of {len} bytes (1..={max})")) } else { Ok(len) }
}

/// Decodes a frame body; anything but exactly one message is an error.
pub fn decode<T: for<'de> Deserialize<'de>>(body: &[u8]) -> Result<T, String> {
    match postcard::take_from_bytes::<T>(body) {
        Ok((msg, [])) => Ok(msg),
        Ok((_, rest)) => Err(format!("{} trailing bytes", rest.len())),
        Err(e) => Err(format!("undecodable ({} bytes): {e}", body.len())),
    }
}

/// The code as both sides key the exchange with: upper case, without dashes or spaces.
pub fn normalize_code(code: &str) -> String {
    code.chars().filter(|c| !c.is_whitespace() && *c != '-').map(|c| c.to_ascii_uppercase()).collect()
}

/// Letters in a normalized join code: a room of [`ROOM_LEN`] and a secret of 8.
pub const CODE_LEN: usize = 12;
/// Letters of the room, the code's first group.
pub const ROOM_LEN: usize = 4;

/// The room a join code names (its first group), or what is wrong with the code.
pub fn room_of(code: &str) -> Result<String, String> {
    let code = normalize_code(code);
    if code.len() != CODE_LEN || !code.chars().all(|c| c.is_ascii_alphanumeric()) {
        return Err(format!(
            "a join code has {CODE_LEN} letters and digits, like K7QX-2M4P-R9TC (got {} characters)",
            code.chars().count()
        ));
    }
    Ok(code[..ROOM_LEN].to_owned())
}

/// The fixed password of the create exchange (no join code can equal it: codes have no colon).
fn create_password() -> Password {
    Password::new(b"create:phantom-heist session")
}

/// A ticket as a SPAKE2 password: prefixed, so no join code can ever equal one.
fn ticket_password(ticket: &SeatTicket) -> Password {
    Password::new(format!("seat:{}", ticket.to_hex()))
}

fn identities() -> (Identity, Identity) {
    (Identity::new(b"phantom-heist player"), Identity::new(b"phantom-heist host"))
}

/// One side of the SPAKE2 exchange, started.
pub struct Pake(Spake2<Ed25519Group>);

impl Pake {
    /// The client's side for `code`, and its message.
    pub fn client(code: &str) -> (Self, Vec<u8>) {
        let (a, b) = identities();
        let (state, msg) = Spake2::<Ed25519Group>::start_a(&Password::new(normalize_code(code)), &a, &b);
        (Self(state), msg)
    }

    /// The server's side for `code`, and its message.
    pub fn server(code: &str) -> (Self, Vec<u8>) {
        let (a, b) = identities();
        let (state, msg) = Spake2::<Ed25519Group>::start_b(&Password::new(normalize_code(code)), &a, &b);
        (Self(state), msg)
    }

    /// The client's side of a resume, keyed by its seat ticket.
    pub fn client_ticket(ticket: &SeatTicket) -> (Self, Vec<u8>) {
        let (a, b) = identities();
        let (state, msg) = Spake2::<Ed25519Group>::start_a(&ticket_password(ticket), &a, &b);
        (Self(state), msg)
    }

    /// The client's side of the create exchange.
    pub fn client_create() -> (Self, Vec<u8>) {
        let (a, b) = identities();
        let (state, msg) = Spake2::<Ed25519Group>::start_a(&create_password(), &a, &b);
        (Self(state), msg)
    }

    /// The server's side of the create exchange.
    pub fn server_create() -> (Self, Vec<u8>) {
        let (a, b) = identities();
        let (state, msg) = Spake2::<Ed25519Group>::start_b(&create_password(), &a, &b);
        (Self(state), msg)
    }

    /// The server's side of a resume, keyed by the seat's ticket.
    pub fn server_ticket(ticket: &SeatTicket) -> (Self, Vec<u8>) {
        let (a, b) = identities();
        let (state, msg) = Spake2::<Ed25519Group>::start_b(&ticket_password(ticket), &a, &b);
        (Self(state), msg)
    }

    /// Finishes with the other side's message and the two frame bodies sent so far (hello, challenge).
    pub fn finish(self, theirs: &[u8], hello: &[u8], challenge: &[u8]) -> Result<JoinKeys, String> {
        let shared = self.0.finish(theirs).map_err(|e| format!("bad key exchange message: {e:?}"))?;
        let mut transcript = blake3::Hasher::new();
        transcript.update(&(hello.len() as u32).to_be_bytes());
        transcript.update(hello);
        transcript.update(challenge);
        let transcript = transcript.finalize();
        let confirm = blake3::derive_key("phantom-heist join v2 client confirm", &shared);
        let seal = blake3::derive_key("phantom-heist join v2 token seal", &shared);
        Ok(JoinKeys {
            client_mac: blake3::keyed_hash(&confirm, transcript.as_bytes()),
            seal: blake3::keyed_hash(&seal, transcript.as_bytes()).into(),
        })
    }
}

/// What the exchange derives from the shared key and the transcript.
pub struct JoinKeys {
    /// The client's confirmation (compared in constant time).
    pub client_mac: blake3::Hash,
    /// Key sealing the token.
    seal: [u8; 32],
}

impl JoinKeys {
    /// Seals `token` (single use key: the nonce is fixed).
    pub fn seal(&self, token: &[u8]) -> Result<Vec<u8>, String> {
        use chacha20poly1305::aead::{Aead, KeyInit};
        let cipher = chacha20poly1305::ChaCha20Poly1305::new((&self.seal).into());
        cipher.encrypt(&[0u8; 12].into(), token).map_err(|e| format!("cannot seal the token: {e}"))
    }

    /// Opens a sealed token; `None` when it was not sealed with this key.
    pub fn open(&self, sealed: &[u8]) -> Option<Vec<u8>> {
        use chacha20poly1305::aead::{Aead, KeyInit};
        let cipher = chacha20poly1305::ChaCha20Poly1305::new((&self.seal).into());
        cipher.decrypt(&[0u8; 12].into(), sealed).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exchange(client_code: &str, server_code: &str) -> (JoinKeys, JoinKeys) {
        let (client, a) = Pake::client(client_code);
        let (server, b) = Pake::server(server_code);
        let room = room_of(client_code).unwrap();
        let hello =
            postcard::to_allocvec(&JoinMsg::Hello { version: JOIN_VERSION, room, role: Role::Vive, pake: a.clone() })
                .unwrap();
        let challenge = postcard::to_allocvec(&JoinReply::Challenge { pake: b.clone() }).unwrap();
        (client.finish(&b, &hello, &challenge).unwrap(), server.finish(&a, &hello, &challenge).unwrap())
    }

    #[test]
    fn the_same_code_gives_the_same_keys_however_it_is_typed() {
        let (c, s) = exchange("k7qx 2m4p r9tc", "K7QX-2M4P-R9TC");
        assert_eq!(c.client_mac, s.client_mac);
        let sealed = s.seal(b"token bytes").unwrap();
        assert_eq!(c.open(&sealed).as_deref(), Some(&b"token bytes"[..]));
    }

    #[test]
    fn a_wrong_code_gives_other_keys() {
        let (c, s) = exchange("K7QX-2M4P-R9TD", "K7QX-2M4P-R9TC");
        assert_ne!(c.client_mac, s.client_mac);
        assert_eq!(c.open(&s.seal(b"token").unwrap()), None);
    }

    #[test]
    fn a_resume_is_keyed_by_the_ticket_and_only_the_same_ticket_agrees() {
        let keys = |client: &SeatTicket, server: &SeatTicket| {
            let (c, a) = Pake::client_ticket(client);
            let (s, b) = Pake::server_ticket(server);
            (c.finish(&b, b"resume", b"challenge").unwrap(), s.finish(&a, b"resume", b"challenge").unwrap())
        };
        let ticket = SeatTicket::random();
        let (c, s) = keys(&ticket, &ticket);
        assert_eq!(c.client_mac, s.client_mac);
        let (c, s) = keys(&SeatTicket::random(), &ticket);
        assert_ne!(c.client_mac, s.client_mac);
    }

    #[test]
    fn a_code_names_its_room_and_a_malformed_code_says_what_is_wrong() {
        assert_eq!(room_of("k7qx-2m4p-r9tc").as_deref(), Ok("K7QX"));
        assert_eq!(room_of(" K7QX 2M4P R9TC ").as_deref(), Ok("K7QX"));
        for bad in ["K7QX-2M4P", "K7QX-2M4P-R9TC-1", "K7Q!-2M4P-R9TC", ""] {
            let e = room_of(bad).unwrap_err();
            assert!(e.contains("12 letters and digits"), "{bad}: {e}");
        }
    }

    #[test]
    fn the_create_exchange_agrees_on_a_key_without_any_code() {
        let (c, a) = Pake::client_create();
        let (s, b) = Pake::server_create();
        let (c, s) = (c.finish(&b, b"create", b"challenge").unwrap(), s.finish(&a, b"create", b"challenge").unwrap());
        assert_eq!(c.client_mac, s.client_mac);
        let sealed = s.seal(b"code and token").unwrap();
        assert_eq!(c.open(&sealed).as_deref(), Some(&b"code and token"[..]));
    }

    #[test]
    fn frames_carry_exactly_one_message() {
        let f = frame(&JoinReply::Refused(JoinRefusal::WrongCode));
        let len = frame_len([f[0], f[1]], MAX_FRAME).unwrap();
        assert_eq!(decode::<JoinReply>(&f[2..2 + len]), Ok(JoinReply::Refused(JoinRefusal::WrongCode)));
        assert!(decode::<JoinReply>(&[f[2..].to_vec(), vec![0]].concat()).is_err());
        assert!(frame_len([0, 0], MAX_FRAME).is_err());
        assert!(frame_len([0xFF, 0xFF], MAX_FRAME).is_err());
    }
}
