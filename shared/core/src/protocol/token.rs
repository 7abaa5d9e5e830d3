//! What travels inside a netcode connect token: the role granted and the session it belongs to, signed
//! by the server's key (the token is obtained through the join exchange, [`super::join`]).

use super::ids::Role;

/// First bytes of our token user data.
pub const USER_DATA_MAGIC: [u8; 4] = *b"PHST";

/// The 256 bytes of user data inside a connect token, as the server reads them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TokenUserData {
    /// Role granted.
    pub role: Role,
    /// Session the token belongs to.
    pub session: u64,
}

impl TokenUserData {
    /// Encodes into netcode's 256-byte user data.
    pub fn encode(&self) -> [u8; 256] {
        let mut out = [0u8; 256];
        out[..4].copy_from_slice(&USER_DATA_MAGIC);
        out[4] = 1; // version
        out[5] = self.role.to_byte();
        out[6..14].copy_from_slice(&self.session.to_le_bytes());
        out
    }

    /// Decodes; None when the bytes are not ours.
    pub fn decode(bytes: &[u8; 256]) -> Option<Self> {
        if bytes[..4] != USER_DATA_MAGIC || bytes[4] != 1 {
            return None;
        }
        let role = Role::from_byte(bytes[5])?;
        let session = u64::from_le_bytes(bytes[6..14].try_into().ok()?);
        Some(Self { role, session })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn user_data_round_trips_and_rejects_foreign_bytes() {
        let u = TokenUserData { role: Role::Phantom, session: 0xDEAD_BEEF };
        assert_eq!(TokenUserData::decode(&u.encode()), Some(u));
        assert_eq!(TokenUserData::decode(&[0u8; 256]), None);
        let mut bad_role = u.encode();
        bad_role[5] = 9;
        assert_eq!(TokenUserData::decode(&bad_role), None);
    }
}
