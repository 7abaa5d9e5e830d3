//! Why joining failed.

use thiserror::Error;

/// Why a client could not join.
#[derive(Debug, Error)]
pub enum JoinError {
    /// The token endpoint could not be reached or did not answer in time.
    #[error("cannot reach the token endpoint at {addr}: {cause}")]
    Unreachable {
        /// Endpoint address.
        addr: std::net::SocketAddr,
        /// Cause (in the message, like every variant's, so a chain printed with `{:#}` says it once).
        cause: std::io::Error,
    },
    /// The endpoint refused (wrong code, role taken...).
    #[error("the host refused to let us join: {0}")]
    Refused(heist_shared::protocol::join::JoinRefusal),
    /// The join code cannot be one (before anything is sent).
    #[error("{0}")]
    BadCode(String),
    /// The endpoint's answer was not understood.
    #[error("the token endpoint sent something we do not understand: {0}")]
    BadResponse(String),
    /// The token lists no server.
    #[error("the connect token names no server address")]
    NoServerAddress,
    /// No local UDP socket.
    #[error("cannot open a UDP socket: {0}")]
    Socket(std::io::Error),
    /// Netcode refused to start.
    #[error("cannot start the netcode client: {0}")]
    Transport(String),
}
