//! What travels inside a netcode connect token: the role granted, the session it belongs to and, for a
//! player coming back, the seat ticket the server checked — all signed by the server's key (the token is
//! obtained through the join exchange, [`super::join`]).

use serde::{Deserialize, Serialize};

use super::ids::Role;

/// First bytes of our token user data.
pub const USER_DATA_MAGIC: [u8; 4] = *b"PHST";
/// Version of the user data layout.
const USER_DATA_VERSION: u8 = 2;

/// A seat ticket: the secret the server hands a player with their first admission to a session, for that
/// seat (role) of that session only. Whoever holds it may take the seat back after a lost connection while
/// the server holds it (see `docs/rules.md`, "Seats"); nobody else can.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct SeatTicket(pub [u8; 16]);

impl SeatTicket {
    /// A fresh ticket from the operating system's random source (128 bits: never guessed).
    pub fn random() -> Self {
        Self(rand::random())
    }

    /// The seat's public name: a keyed hash of the ticket, sent in clear by a resume so the server finds
    /// the session whose seat it is, and from which the ticket cannot be recovered.
    pub fn public_id(&self) -> [u8; 16] {
        let hash = blake3::keyed_hash(&blake3::derive_key("phantom-heist seat id", b""), &self.0);
        let mut id = [0u8; 16];
        id.copy_from_slice(&hash.as_bytes()[..16]);
        id
    }

    /// Lowercase hex, as the seat cache stores it and the resume exchange is keyed with.
    pub fn to_hex(&self) -> String {
        self.0.iter().map(|b| format!("{b:02x}")).collect()
    }

    /// Parses [`SeatTicket::to_hex`]'s form (surrounding white space ignored).
    pub fn from_hex(text: &str) -> Result<Self, String> {
        let text = text.trim();
        if text.len() != 32 || !text.is_ascii() {
            return Err(format!("a seat ticket is 32 hex digits, not {} characters", text.chars().count()));
        }
        let mut out = [0u8; 16];
        for (i, byte) in out.iter_mut().enumerate() {
            *byte = u8::from_str_radix(&text[2 * i..2 * i + 2], 16)
                .map_err(|_| format!("a seat ticket is hex digits only: {:?}", &text[2 * i..2 * i + 2]))?;
        }
        Ok(Self(out))
    }
}

impl std::fmt::Debug for SeatTicket {
    /// Never prints the secret (logs and panics show only that there is one).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SeatTicket(…)")
    }
}

/// The 256 bytes of user data inside a connect token, as the server reads them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TokenUserData {
    /// Role granted.
    pub role: Role,
    /// Session the token belongs to.
    pub session: u64,
    /// The seat ticket of a player coming back (the resume exchange checked it); `None` for a first join.
    pub ticket: Option<SeatTicket>,
}

impl TokenUserData {
    /// Encodes into netcode's 256-byte user data.
    pub fn encode(&self) -> [u8; 256] {
        let mut out = [0u8; 256];
        out[..4].copy_from_slice(&USER_DATA_MAGIC);
        out[4] = USER_DATA_VERSION;
        out[5] = self.role.to_byte();
        out[6..14].copy_from_slice(&self.session.to_le_bytes());
        if let Some(ticket) = self.ticket {
            out[14] = 1;
            out[15..31].copy_from_slice(&ticket.0);
        }
        out
    }

    /// Decodes; None when the bytes are not ours.
    pub fn decode(bytes: &[u8; 256]) -> Option<Self> {
        if bytes[..4] != USER_DATA_MAGIC || bytes[4] != USER_DATA_VERSION {
            return None;
        }
        let role = Role::from_byte(bytes[5])?;
        let session = u64::from_le_bytes(bytes[6..14].try_into().ok()?);
        let ticket = match bytes[14] {
            0 => None,
            1 => Some(SeatTicket(bytes[15..31].try_into().ok()?)),
            _ => return None,
        };
        Some(Self { role, session, ticket })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn user_data_round_trips_and_rejects_foreign_bytes() {
        let u = TokenUserData { role: Role::Phantom, session: 0xDEAD_BEEF, ticket: None };
        assert_eq!(TokenUserData::decode(&u.encode()), Some(u));
        let back = TokenUserData { ticket: Some(SeatTicket([7; 16])), ..u };
        assert_eq!(TokenUserData::decode(&back.encode()), Some(back));
        assert_eq!(TokenUserData::decode(&[0u8; 256]), None);
        let mut bad_role = u.encode();
        bad_role[5] = 9;
        assert_eq!(TokenUserData::decode(&bad_role), None);
        let mut bad_flag = u.encode();
        bad_flag[14] = 2;
        assert_eq!(TokenUserData::decode(&bad_flag), None);
    }

    #[test]
    fn a_ticket_reads_back_from_hex_and_never_prints_itself() {
        let t = SeatTicket::random();
        assert_eq!(SeatTicket::from_hex(&format!(" {}\n", t.to_hex())), Ok(t));
        assert_ne!(SeatTicket::random(), t);
        assert!(SeatTicket::from_hex("abc").unwrap_err().contains("32 hex digits"));
        assert!(SeatTicket::from_hex(&"zz".repeat(16)).unwrap_err().contains("hex digits only"));
        assert_eq!(format!("{t:?}"), "SeatTicket(…)");
    }
}
