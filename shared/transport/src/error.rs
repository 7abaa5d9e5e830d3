//! Why a datagram or a payload was turned away, as data.

use thiserror::Error;

use crate::datagram::PacketKind;

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

/// Why a decrypted renet packet never reached renet.
#[derive(Clone, Copy, Debug, Error, PartialEq, Eq)]
pub enum PayloadRefusal {
    /// The packet ended inside a field.
    #[error("renet packet truncated")]
    Truncated,
    /// A slice numbered past its message's slice count (the renet 2.0.1 panic).
    #[error("slice {index} of a message of {count} slices")]
    SliceOutOfRange {
        /// Slice index.
        index: u64,
        /// Slices in the message.
        count: u64,
    },
    /// A message cut into more slices than this side accepts.
    #[error("message of {count} slices (at most {max})")]
    TooManySlices {
        /// Slices announced.
        count: u64,
        /// The limit.
        max: u64,
    },
    /// A slice whose message earlier announced another slice count (renet would index past its buffer).
    #[error("message {message_id} announced {was} slices, now {now}")]
    SliceCountChanged {
        /// The message.
        message_id: u64,
        /// Count first announced.
        was: u64,
        /// Count in this slice.
        now: u64,
    },
    /// A slice of a message older than the ones this side still tracks.
    #[error("slice of an old message {0}")]
    StaleSlice(u64),
    /// Over this connection's datagram rate.
    #[error("datagrams over the connection's rate limit")]
    RateLimited,
}

/// Why a transport stopped.
#[derive(Debug, Error)]
pub enum TransportError {
    /// Netcode gave up or failed.
    #[error("netcode: {0}")]
    Netcode(#[from] renetcode::NetcodeError),
    /// renet gave up on the connection.
    #[error("renet: {0}")]
    Renet(renet::DisconnectReason),
    /// The socket failed.
    #[error("socket: {0}")]
    Io(#[from] std::io::Error),
}
