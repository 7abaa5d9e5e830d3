//! One connection's join exchange, from the first byte to the token (or the refusal).

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use heist_shared::protocol::join::{self, JOIN_VERSION, JoinMsg, JoinRefusal, JoinReply, NewSession, Pake};
use heist_shared::protocol::{PROTOCOL_ID, Role, SeatTicket, TokenUserData};
use heist_transport::limit::address_key;
use heist_transport::renetcode::ConnectToken;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

use super::super::registry::SessionEntry;
use super::guesses::Outcome;
use super::shared::{Closer, Shared, TokenConfig, lock};

/// Largest frame a client sends, bytes (a hello is ~40).
const MAX_CLIENT_FRAME: usize = 256;
/// Seconds a token stays valid.
const TOKEN_EXPIRE_S: u64 = 300;
/// Seconds of silence after which netcode drops a client (and a client its server): long enough for a
/// poor link's worst gap (keep-alives go 10 times a second), short enough that a dead player's seat is
/// kept, and a running heist paused, within seconds.
const TIMEOUT_S: i32 = 6;

/// Why an exchange ended without a token.
enum Failure {
    /// Refused: the client is told why.
    Refused(JoinRefusal),
    /// The connection broke or the client sent something that is not a frame.
    Broken(String),
}

impl From<std::io::Error> for Failure {
    fn from(e: std::io::Error) -> Self {
        Failure::Broken(e.to_string())
    }
}

/// Serves one connection within the deadline.
pub(super) async fn serve(mut stream: TcpStream, peer: SocketAddr, shared: Arc<Shared>, _closer: Closer) {
    let deadline = shared.config.limits.deadline;
    let result = match tokio::time::timeout(deadline, exchange(&mut stream, peer, &shared)).await {
        Ok(r) => r,
        Err(_) => Err(Failure::Broken(format!("no complete exchange within {} s", deadline.as_secs_f32()))),
    };
    match result {
        Ok(role) => log::info!("token endpoint: gave a {role} token to {peer}"),
        Err(Failure::Refused(refusal)) => {
            shared.config.metrics.refuse("join", refusal.kind());
            shared.refused(peer, &refusal);
            let _ = tokio::time::timeout(deadline, stream.write_all(&join::frame(&JoinReply::Refused(refusal)))).await;
        }
        Err(Failure::Broken(why)) => {
            shared.config.metrics.refuse("exchange", "broken");
            shared.refused(peer, &why);
        }
    }
}

/// A guess in flight; counted as abandoned unless it ends with a verdict (a dropped task included).
struct Attempt<'a> {
    shared: &'a Shared,
    peer: SocketAddr,
    ended: bool,
}

impl<'a> Attempt<'a> {
    fn begin(shared: &'a Shared, peer: SocketAddr) -> Result<Self, Failure> {
        lock(&shared.guesses).begin(address_key(peer.ip()), shared.now_s()).map_err(Failure::Refused)?;
        Ok(Self { shared, peer, ended: false })
    }

    /// Records the outcome; returns the seconds to wait before answering.
    fn end(mut self, outcome: Outcome) -> f64 {
        self.ended = true;
        let verdict = lock(&self.shared.guesses).end(address_key(self.peer.ip()), outcome, self.shared.now_s());
        if let Some(period) = verdict.locked_for_s {
            let why = format!(
                "{} wrong join codes: refusing this address for {period:.0} s",
                self.shared.config.limits.guesses.max
            );
            self.shared.refused(self.peer, &why);
        }
        verdict.delay_s
    }
}

impl Drop for Attempt<'_> {
    fn drop(&mut self) {
        if !self.ended {
            lock(&self.shared.guesses).end(address_key(self.peer.ip()), Outcome::Abandoned, self.shared.now_s());
        }
    }
}

async fn read_frame(stream: &mut TcpStream) -> Result<Vec<u8>, Failure> {
    let mut header = [0u8; 2];
    stream.read_exact(&mut header).await?;
    let len = join::frame_len(header, MAX_CLIENT_FRAME).map_err(|e| Failure::Refused(JoinRefusal::BadRequest(e)))?;
    let mut body = vec![0u8; len];
    stream.read_exact(&mut body).await?;
    Ok(body)
}

fn decode(body: &[u8]) -> Result<JoinMsg, Failure> {
    join::decode(body).map_err(|e| Failure::Refused(JoinRefusal::BadRequest(e)))
}

/// What the opening asked for, once its session is found.
enum Request {
    /// A seat in an open session, with its code.
    Join(SessionEntry),
    /// A kept (or still taken) seat back, with its ticket.
    Resume(SessionEntry, SeatTicket),
    /// A new session.
    Create,
}

/// The exchange itself: hello (or resume, or create), challenge, confirmation, token.
async fn exchange(stream: &mut TcpStream, peer: SocketAddr, shared: &Shared) -> Result<Role, Failure> {
    let hello = read_frame(stream).await?;
    let opening = decode(&hello)?;
    let (version, role) = match &opening {
        JoinMsg::Hello { version, role, .. } | JoinMsg::Resume { version, role, .. } => (*version, *role),
        JoinMsg::Create { version, role, .. } => (*version, *role),
        JoinMsg::Confirm { .. } => {
            return Err(Failure::Refused(JoinRefusal::BadRequest("the exchange starts with a hello".into())));
        }
    };
    if version != JOIN_VERSION {
        return Err(Failure::Refused(JoinRefusal::Version { server: JOIN_VERSION, client: version }));
    }
    let registry = &shared.config.registry;
    let (request, theirs, server, ours, attempt) = match opening {
        JoinMsg::Hello { room, pake, .. } => {
            let attempt = Attempt::begin(shared, peer)?;
            let Some(entry) = registry.by_room(&room) else {
                // No such session: as wrong as a wrong code, and counted like one (rooms are not probed
                // for free).
                let delay = attempt.end(Outcome::Wrong);
                tokio::time::sleep(std::time::Duration::from_secs_f64(delay)).await;
                return Err(Failure::Refused(JoinRefusal::WrongCode));
            };
            let code = entry.codes.current();
            if code.is_expired() {
                log::warn!(
                    "token endpoint: {peer} tried to join but the join code has expired (type `rotate` for a new one)"
                );
                return Err(Failure::Refused(JoinRefusal::CodeExpired));
            }
            let (server, ours) = Pake::server(&code.code);
            (Request::Join(entry), pake, server, ours, Some(attempt))
        }
        // A resume is keyed by the seat's ticket, and works after the code expired or was rotated.
        JoinMsg::Resume { seat, pake, .. } => {
            let (entry, ticket) = registry.by_seat(role, &seat).map_err(Failure::Refused)?;
            let attempt = Attempt::begin(shared, peer)?;
            let (server, ours) = Pake::server_ticket(&ticket);
            (Request::Resume(entry, ticket), pake, server, ours, Some(attempt))
        }
        JoinMsg::Create { pake, .. } => {
            let (server, ours) = Pake::server_create();
            (Request::Create, pake, server, ours, None)
        }
        JoinMsg::Confirm { .. } => unreachable!("refused above"),
    };
    let challenge = join::frame(&JoinReply::Challenge { pake: ours });
    stream.write_all(&challenge).await?;
    let confirm = read_frame(stream).await?;
    let JoinMsg::Confirm { mac } = decode(&confirm)? else {
        return Err(Failure::Refused(JoinRefusal::BadRequest("expected the confirmation".into())));
    };
    let keys =
        server.finish(&theirs, &hello, &challenge[2..]).map_err(|e| Failure::Refused(JoinRefusal::BadRequest(e)))?;
    if keys.client_mac != blake3::Hash::from(mac) {
        let wrong = match request {
            Request::Join(_) => JoinRefusal::WrongCode,
            Request::Resume(..) => JoinRefusal::WrongTicket,
            Request::Create => JoinRefusal::BadRequest("the key exchange did not agree".into()),
        };
        if let Some(attempt) = attempt {
            let delay = attempt.end(Outcome::Wrong);
            tokio::time::sleep(std::time::Duration::from_secs_f64(delay)).await;
        }
        return Err(Failure::Refused(wrong));
    }
    if let Some(attempt) = attempt {
        attempt.end(Outcome::Right);
    }
    let internal = |e| Failure::Refused(JoinRefusal::Internal(e));
    let reply = match request {
        Request::Join(entry) => {
            entry.seats.check_join(role).map_err(Failure::Refused)?;
            let token = mint(&shared.config, &entry, role, None).map_err(internal)?;
            JoinReply::Token { sealed: keys.seal(&token).map_err(internal)? }
        }
        Request::Resume(entry, ticket) => {
            let token = mint(&shared.config, &entry, role, Some(ticket)).map_err(internal)?;
            JoinReply::Token { sealed: keys.seal(&token).map_err(internal)? }
        }
        Request::Create => {
            let entry = registry.open(Some(peer.ip())).map_err(Failure::Refused)?;
            log::info!("token endpoint: {peer} created a session ({} open)", registry.len());
            let token = mint(&shared.config, &entry, role, None).map_err(internal)?;
            let created = postcard::to_allocvec(&NewSession { code: entry.codes.current().code, token })
                .map_err(|e| internal(format!("cannot encode the new session: {e}")))?;
            JoinReply::Created { sealed: keys.seal(&created).map_err(internal)? }
        }
    };
    stream.write_all(&join::frame(&reply)).await?;
    Ok(role)
}

/// A connect token for `role` in netcode's wire format.
/// A resume's token carries the seat ticket it proved, for admission to check again.
fn mint(
    config: &TokenConfig,
    session: &SessionEntry,
    role: Role,
    ticket: Option<SeatTicket>,
) -> Result<Vec<u8>, String> {
    let now = SystemTime::now().duration_since(UNIX_EPOCH).unwrap_or_default();
    let user_data = TokenUserData { role, session: session.id, ticket }.encode();
    let server = *config.server_addrs.get(session.shard).ok_or_else(|| format!("no shard {}", session.shard))?;
    let token = ConnectToken::generate(
        now,
        PROTOCOL_ID,
        TOKEN_EXPIRE_S,
        rand::random(),
        TIMEOUT_S,
        vec![server],
        Some(&user_data),
        &config.private_key,
    )
    .map_err(|e| format!("could not mint a token: {e}"))?;
    let mut bytes = Vec::new();
    token.write(&mut bytes).map_err(|e| format!("could not encode the token: {e}"))?;
    Ok(bytes)
}
