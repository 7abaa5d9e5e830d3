//! Why a payload was turned away, as data, and why a transport stopped (a datagram's refusal is
//! [`crate::datagram::DatagramRefusal`], beside its check).

use thiserror::Error;

/// Why a decrypted payload, or a renet packet in it, never reached renet.
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
    /// Over this connection's packet rate.
    #[error("packets over the connection's rate limit")]
    RateLimited,
    /// A payload that is not a whole bundle of renet packets ([`crate::bundle`]); none of it reaches renet.
    #[error("bad bundle: {0}")]
    BadBundle(&'static str),
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
