//! The netcode header of a datagram, checked before netcode reads it.
//!
//! renetcode 2.0.0 trusts the sequence length in a packet's prefix byte and slices an 8-byte buffer with
//! it (`packet.rs:375`): a prefix announcing 9..=15 bytes panics the server when it comes from a pending or
//! connected address; a datagram too short for its announced sequence and tag underflows its tag
//! arithmetic; a sequence near `u64::MAX` overflows its replay window. Every datagram passes
//! [`check_datagram`] first, so netcode only ever sees headers it can parse.

use thiserror::Error;

/// Netcode's authentication tag, bytes.
pub const MAC_BYTES: usize = 16;
/// Largest datagram netcode sends or reads, bytes.
pub const MAX_DATAGRAM_BYTES: usize = 1400;
/// A connection request: prefix, version, protocol id, expiry, nonce, private token data.
pub const CONNECTION_REQUEST_BYTES: usize = 1 + 13 + 8 + 8 + 24 + 1024;
/// The version string every netcode 1.02 connection request starts with.
pub const VERSION_INFO: &[u8; 13] = b"NETCODE 1.02\0";

/// Which way a datagram travels: each side only accepts the packet types the other side sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// From a client to the server.
    ToServer,
    /// From the server to a client.
    ToClient,
}

/// The netcode packet types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PacketKind {
    /// A client asks to connect, showing its connect token (the only unencrypted packet).
    ConnectionRequest,
    /// The server turns a client away.
    ConnectionDenied,
    /// The server's challenge.
    Challenge,
    /// The client's answer to the challenge.
    Response,
    /// Keeps an idle connection alive.
    KeepAlive,
    /// Carries a renet packet.
    Payload,
    /// Ends the connection.
    Disconnect,
}

impl PacketKind {
    fn from_type(t: u8) -> Option<Self> {
        Some(match t {
            0 => Self::ConnectionRequest,
            1 => Self::ConnectionDenied,
            2 => Self::Challenge,
            3 => Self::Response,
            4 => Self::KeepAlive,
            5 => Self::Payload,
            6 => Self::Disconnect,
            _ => return None,
        })
    }

    /// True when this kind travels in `direction`.
    pub fn travels(self, direction: Direction) -> bool {
        match self {
            Self::ConnectionRequest | Self::Response => direction == Direction::ToServer,
            Self::ConnectionDenied | Self::Challenge => direction == Direction::ToClient,
            Self::KeepAlive | Self::Payload | Self::Disconnect => true,
        }
    }
}

/// Why a datagram never reached netcode.
#[derive(Clone, Copy, Debug, Error, PartialEq, Eq)]
pub enum DatagramRefusal {
    /// Shorter than its header and tag.
    #[error("datagram of {0} bytes is too short for its header")]
    TooShort(usize),
    /// Longer than netcode's largest packet.
    #[error("datagram of {0} bytes is longer than netcode's 1400")]
    TooLong(usize),
    /// The prefix names no netcode packet type.
    #[error("unknown netcode packet type {0}")]
    UnknownType(u8),
    /// A packet type the other side never sends.
    #[error("{0:?} packets do not travel this way")]
    WrongDirection(PacketKind),
    /// The prefix announces a sequence longer than 8 bytes (the renetcode 2.0.0 panic).
    #[error("sequence length {0} in the prefix (at most 8)")]
    BadSequenceLength(u8),
    /// A sequence number no connection reaches (netcode's replay window overflows near `u64::MAX`).
    #[error("sequence number beyond 2^63")]
    SequenceOutOfRange,
    /// A connection request whose prefix is not 0.
    #[error("connection request with prefix {0:#04x}")]
    BadPrefix(u8),
    /// A connection request of the wrong size.
    #[error("connection request of {0} bytes (must be 1078)")]
    BadRequestSize(usize),
    /// A connection request for another protocol version.
    #[error("connection request for another netcode version")]
    BadVersion,
    /// From an address that is not the server's (client side).
    #[error("datagram from an address that is not the server")]
    NotFromServer,
    /// Over this address's rate of connection requests, or the server's.
    #[error("connection requests over the rate limit")]
    RateLimited,
}

/// Checks a datagram's netcode header: size, packet type, direction, sequence length, and for a connection
/// request its exact size and version. Cheap and allocation-free; says nothing about the encrypted part.
pub fn check_datagram(bytes: &[u8], direction: Direction) -> Result<PacketKind, DatagramRefusal> {
    if bytes.len() < 2 + MAC_BYTES {
        return Err(DatagramRefusal::TooShort(bytes.len()));
    }
    if bytes.len() > MAX_DATAGRAM_BYTES {
        return Err(DatagramRefusal::TooLong(bytes.len()));
    }
    let prefix = bytes[0];
    let kind = PacketKind::from_type(prefix & 0x0F).ok_or(DatagramRefusal::UnknownType(prefix & 0x0F))?;
    if !kind.travels(direction) {
        return Err(DatagramRefusal::WrongDirection(kind));
    }
    if kind == PacketKind::ConnectionRequest {
        if prefix != 0 {
            return Err(DatagramRefusal::BadPrefix(prefix));
        }
        if bytes.len() != CONNECTION_REQUEST_BYTES {
            return Err(DatagramRefusal::BadRequestSize(bytes.len()));
        }
        if &bytes[1..14] != VERSION_INFO {
            return Err(DatagramRefusal::BadVersion);
        }
        return Ok(kind);
    }
    let sequence_len = usize::from(prefix >> 4);
    if sequence_len > 8 {
        return Err(DatagramRefusal::BadSequenceLength(sequence_len as u8));
    }
    if bytes.len() < 1 + sequence_len + MAC_BYTES {
        return Err(DatagramRefusal::TooShort(bytes.len()));
    }
    // Replay protection adds its window (256) to the sequence before decrypting; near u64::MAX that
    // overflows (renetcode 2.0.0, replay_protection.rs:25). Real sequences count up from 0.
    let mut sequence = [0u8; 8];
    sequence[..sequence_len].copy_from_slice(&bytes[1..1 + sequence_len]);
    if u64::from_le_bytes(sequence) > MAX_SEQUENCE {
        return Err(DatagramRefusal::SequenceOutOfRange);
    }
    Ok(kind)
}

/// Largest packet sequence accepted: far beyond any real connection (2⁶³ packets), far below where
/// netcode's replay window arithmetic overflows.
pub const MAX_SEQUENCE: u64 = 1 << 63;

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> Vec<u8> {
        let mut r = vec![0u8; CONNECTION_REQUEST_BYTES];
        r[1..14].copy_from_slice(VERSION_INFO);
        r
    }

    #[test]
    fn the_crashing_prefix_is_refused_before_netcode_sees_it() {
        let mut d = vec![0xF3];
        d.extend_from_slice(&[0u8; 17]);
        assert_eq!(check_datagram(&d, Direction::ToServer), Err(DatagramRefusal::BadSequenceLength(15)));
        d[0] = 0x93;
        assert_eq!(check_datagram(&d, Direction::ToServer), Err(DatagramRefusal::BadSequenceLength(9)));
    }

    #[test]
    fn well_formed_headers_pass_in_their_direction_only() {
        let mut keep_alive = vec![0x14];
        keep_alive.extend_from_slice(&[0u8; 1 + 8 + MAC_BYTES]);
        assert_eq!(check_datagram(&keep_alive, Direction::ToServer), Ok(PacketKind::KeepAlive));
        let mut challenge = keep_alive.clone();
        challenge[0] = 0x02; // sequence 0 has a zero-length sequence
        assert_eq!(check_datagram(&challenge, Direction::ToClient), Ok(PacketKind::Challenge));
        assert_eq!(
            check_datagram(&challenge, Direction::ToServer),
            Err(DatagramRefusal::WrongDirection(PacketKind::Challenge))
        );
        assert_eq!(check_datagram(&request(), Direction::ToServer), Ok(PacketKind::ConnectionRequest));
        assert!(check_datagram(&request(), Direction::ToClient).is_err());
    }

    #[test]
    fn a_connection_request_must_have_its_exact_size_and_version() {
        let mut short = request();
        short.pop();
        assert_eq!(check_datagram(&short, Direction::ToServer), Err(DatagramRefusal::BadRequestSize(1077)));
        let mut foreign = request();
        foreign[1] = b'X';
        assert_eq!(check_datagram(&foreign, Direction::ToServer), Err(DatagramRefusal::BadVersion));
        let mut prefixed = request();
        prefixed[0] = 0x10;
        assert_eq!(check_datagram(&prefixed, Direction::ToServer), Err(DatagramRefusal::BadPrefix(0x10)));
    }

    #[test]
    fn a_sequence_near_the_end_of_u64_is_refused() {
        let mut d = vec![0x84];
        d.extend_from_slice(&[0xFF; 8]);
        d.extend_from_slice(&[0u8; MAC_BYTES]);
        assert_eq!(check_datagram(&d, Direction::ToServer), Err(DatagramRefusal::SequenceOutOfRange));
        d[8] = 0x7F;
        assert_eq!(check_datagram(&d, Direction::ToServer), Ok(PacketKind::KeepAlive));
    }

    #[test]
    fn unknown_types_and_tiny_or_huge_datagrams_are_refused() {
        assert_eq!(check_datagram(&[0x07; 40], Direction::ToServer), Err(DatagramRefusal::UnknownType(7)));
        assert_eq!(check_datagram(&[0x05; 17], Direction::ToServer), Err(DatagramRefusal::TooShort(17)));
        assert_eq!(check_datagram(&[0x85; 20], Direction::ToServer), Err(DatagramRefusal::TooShort(20)));
        assert_eq!(check_datagram(&[0x05; 1401], Direction::ToServer), Err(DatagramRefusal::TooLong(1401)));
    }
}
