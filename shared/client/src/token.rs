//! Asking the host's token endpoint for a connect token.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::Duration;

use heist_transport::renetcode::ConnectToken;
use heist_shared::protocol::{JoinRequest, JoinResponse, Role};

use crate::JoinError;

/// Longest answer accepted, bytes (a token is 2 KiB; JSON spells each byte as up to 4 characters).
const MAX_RESPONSE: u64 = 16 * 1024;

/// Exchanges `code` + `role` for a connect token at `endpoint` (the host's game address, TCP).
pub fn request_token(
    endpoint: SocketAddr,
    code: &str,
    role: Role,
    timeout: Duration,
) -> Result<ConnectToken, JoinError> {
    let unreachable = |source| JoinError::Unreachable { addr: endpoint, source };
    let stream = TcpStream::connect_timeout(&endpoint, timeout).map_err(unreachable)?;
    stream.set_read_timeout(Some(timeout)).map_err(unreachable)?;
    stream.set_write_timeout(Some(timeout)).map_err(unreachable)?;
    let mut line = serde_json::to_vec(&JoinRequest { code: code.to_owned(), role })
        .map_err(|e| JoinError::BadResponse(e.to_string()))?;
    line.push(b'\n');
    (&stream).write_all(&line).map_err(unreachable)?;
    let mut answer = String::new();
    BufReader::new((&stream).take(MAX_RESPONSE)).read_line(&mut answer).map_err(unreachable)?;
    match serde_json::from_str::<JoinResponse>(answer.trim()) {
        Ok(JoinResponse::Token(bytes)) => {
            ConnectToken::read(&mut bytes.as_slice()).map_err(|e| JoinError::BadResponse(format!("bad token: {e}")))
        }
        Ok(JoinResponse::Refused(reason)) => Err(JoinError::Refused(reason)),
        Err(e) => Err(JoinError::BadResponse(format!("{e} in {:?}", answer.chars().take(80).collect::<String>()))),
    }
}
