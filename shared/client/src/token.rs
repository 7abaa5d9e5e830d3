//! Asking the host's token endpoint for a connect token: the join exchange of
//! [`heist_shared::protocol::join`] (with the join code, or with a seat ticket to come back), client side
//! (blocking, with a timeout on every step).

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::Duration;

use heist_shared::protocol::join::{self, JOIN_VERSION, JoinMsg, JoinReply, MAX_FRAME, NewSession, Pake};
use heist_shared::protocol::{PROTOCOL_ID, Role, SeatTicket};
use heist_transport::renetcode::ConnectToken;

use crate::JoinError;

/// Exchanges `code` + `role` for a connect token at `endpoint` (the host's game address, TCP).
pub fn request_token(
    endpoint: SocketAddr,
    code: &str,
    role: Role,
    timeout: Duration,
) -> Result<ConnectToken, JoinError> {
    let room = join::room_of(code).map_err(JoinError::BadCode)?;
    let (pake, ours) = Pake::client(code);
    let sealed = exchange(endpoint, JoinMsg::Hello { version: JOIN_VERSION, room, role, pake: ours }, pake, timeout)?;
    open_token(&sealed)
}

/// Asks the server at `endpoint` to create a new session in which this client plays `role`; returns the
/// session's join code (for the partner) and this client's connect token.
pub fn create_session(
    endpoint: SocketAddr,
    role: Role,
    timeout: Duration,
) -> Result<(String, ConnectToken), JoinError> {
    let (pake, ours) = Pake::client_create();
    let plain = exchange(endpoint, JoinMsg::Create { version: JOIN_VERSION, role, pake: ours }, pake, timeout)?;
    let created: NewSession = join::decode(&plain).map_err(JoinError::BadResponse)?;
    join::room_of(&created.code).map_err(|e| JoinError::BadResponse(format!("the new session's code: {e}")))?;
    Ok((created.code, open_token(&created.token)?))
}

/// Exchanges a seat ticket for a connect token that takes the kept (or still taken) `role` seat back at
/// `endpoint`: the resume exchange, keyed by the ticket instead of the join code.
pub fn request_resume_token(
    endpoint: SocketAddr,
    role: Role,
    ticket: &SeatTicket,
    timeout: Duration,
) -> Result<ConnectToken, JoinError> {
    let (pake, ours) = Pake::client_ticket(ticket);
    let seat = ticket.public_id();
    let sealed = exchange(endpoint, JoinMsg::Resume { version: JOIN_VERSION, role, seat, pake: ours }, pake, timeout)?;
    open_token(&sealed)
}

/// Runs the exchange opened by `opening`; returns the plain text of the server's sealed last reply.
fn exchange(endpoint: SocketAddr, opening: JoinMsg, pake: Pake, timeout: Duration) -> Result<Vec<u8>, JoinError> {
    let unreachable = |cause| JoinError::Unreachable { addr: endpoint, cause };
    let mut stream = TcpStream::connect_timeout(&endpoint, timeout).map_err(unreachable)?;
    stream.set_read_timeout(Some(timeout)).map_err(unreachable)?;
    stream.set_write_timeout(Some(timeout)).map_err(unreachable)?;

    let hello = join::frame(&opening);
    stream.write_all(&hello).map_err(unreachable)?;
    let challenge = read_frame(&mut stream).map_err(unreachable)?;
    let theirs = match decode(&challenge)? {
        JoinReply::Challenge { pake } => pake,
        JoinReply::Refused(r) => return Err(JoinError::Refused(r)),
        JoinReply::Token { .. } | JoinReply::Created { .. } => {
            return Err(JoinError::BadResponse("a token before the key exchange".into()));
        }
    };
    let keys = pake.finish(&theirs, &hello[2..], &challenge).map_err(JoinError::BadResponse)?;
    stream.write_all(&join::frame(&JoinMsg::Confirm { mac: *keys.client_mac.as_bytes() })).map_err(unreachable)?;
    let creating = matches!(opening, JoinMsg::Create { .. });
    let sealed = match decode(&read_frame(&mut stream).map_err(unreachable)?)? {
        JoinReply::Token { sealed } if !creating => sealed,
        JoinReply::Created { sealed } if creating => sealed,
        JoinReply::Token { .. } | JoinReply::Created { .. } => {
            return Err(JoinError::BadResponse("an answer to another request".into()));
        }
        JoinReply::Refused(r) => return Err(JoinError::Refused(r)),
        JoinReply::Challenge { .. } => return Err(JoinError::BadResponse("a second challenge".into())),
    };
    keys.open(&sealed).ok_or_else(|| JoinError::BadResponse("the answer was not sealed for us".into()))
}

/// Reads and checks a connect token in netcode's wire format.
fn open_token(bytes: &[u8]) -> Result<ConnectToken, JoinError> {
    let token = ConnectToken::read(&mut &bytes[..]).map_err(|e| JoinError::BadResponse(format!("bad token: {e}")))?;
    check(&token)?;
    Ok(token)
}

fn read_frame(stream: &mut TcpStream) -> std::io::Result<Vec<u8>> {
    let mut header = [0u8; 2];
    stream.read_exact(&mut header)?;
    let len = join::frame_len(header, MAX_FRAME).map_err(std::io::Error::other)?;
    let mut body = vec![0u8; len];
    stream.read_exact(&mut body)?;
    Ok(body)
}

fn decode(body: &[u8]) -> Result<JoinReply, JoinError> {
    join::decode(body).map_err(JoinError::BadResponse)
}

/// What netcode's client would otherwise panic on or silently fail with.
fn check(token: &ConnectToken) -> Result<(), JoinError> {
    if token.protocol_id != PROTOCOL_ID {
        return Err(JoinError::BadResponse("the token is for another game version".into()));
    }
    if token.expire_timestamp < token.create_timestamp {
        return Err(JoinError::BadResponse("the token expires before it was made".into()));
    }
    if token.server_addresses[0].is_none() {
        return Err(JoinError::NoServerAddress);
    }
    Ok(())
}
