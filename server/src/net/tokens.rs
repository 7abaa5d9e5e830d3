//! The token endpoint: exchanges a join code (+ role) for a netcode connect token over TCP.
//!
//! One JSON line in, one JSON line out. Runs on its own thread; never blocks the game loop.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use heist_transport::renetcode::ConnectToken;
use heist_shared::protocol::{JoinRequest, JoinResponse, PROTOCOL_ID, Role, TokenUserData};

/// Longest request line accepted, bytes.
const MAX_REQUEST: u64 = 1024;
/// Seconds a token stays valid.
const TOKEN_EXPIRE_S: u64 = 300;
/// Seconds of silence after which netcode drops a client.
const TIMEOUT_S: i32 = 15;

/// Which roles are currently taken, shared by the game server and the token endpoint.
#[derive(Clone, Debug, Default)]
pub struct RoleTable(Arc<Mutex<[bool; 2]>>);

impl RoleTable {
    fn index(role: Role) -> usize {
        usize::from(role.to_byte() - 1)
    }

    /// Marks a role taken or free.
    pub fn set(&self, role: Role, taken: bool) {
        if let Ok(mut t) = self.0.lock() {
            t[Self::index(role)] = taken;
        }
    }

    /// True when someone plays `role`.
    pub fn is_taken(&self, role: Role) -> bool {
        self.0.lock().map(|t| t[Self::index(role)]).unwrap_or(true)
    }
}

/// What the endpoint needs to mint tokens.
#[derive(Clone)]
pub struct TokenConfig {
    /// The join code players must present.
    pub code: String,
    /// Netcode private key shared with the game server.
    pub private_key: [u8; 32],
    /// The game server's public UDP address (must equal the server's `public_addresses`).
    pub server_addr: SocketAddr,
    /// Session id written into every token.
    pub session: u64,
    /// Roles in play.
    pub roles: RoleTable,
}

/// A running token endpoint; stops when dropped.
pub struct TokenService {
    /// Address it listens on.
    pub addr: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl TokenService {
    /// Binds `bind` and serves on a background thread.
    pub fn spawn(bind: SocketAddr, config: TokenConfig) -> std::io::Result<Self> {
        let listener = TcpListener::bind(bind)?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let stop = Arc::new(AtomicBool::new(false));
        let stop2 = stop.clone();
        let next_id = AtomicU64::new(rand::random::<u32>() as u64 + 1);
        let thread = std::thread::Builder::new().name("token-endpoint".into()).spawn(move || {
            while !stop2.load(Ordering::Relaxed) {
                match listener.accept() {
                    Ok((stream, peer)) => {
                        if let Err(e) = serve(stream, &config, &next_id) {
                            log::warn!("token endpoint: request from {peer} failed: {e}");
                        }
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                        std::thread::sleep(Duration::from_millis(5));
                    }
                    Err(e) => log::warn!("token endpoint: accept failed: {e}"),
                }
            }
        })?;
        Ok(Self { addr, stop, thread: Some(thread) })
    }
}

impl Drop for TokenService {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn serve(stream: TcpStream, config: &TokenConfig, next_id: &AtomicU64) -> std::io::Result<()> {
    stream.set_nonblocking(false)?;
    stream.set_read_timeout(Some(Duration::from_secs(2)))?;
    stream.set_write_timeout(Some(Duration::from_secs(2)))?;
    let mut line = String::new();
    BufReader::new((&stream).take(MAX_REQUEST)).read_line(&mut line)?;
    let response = answer(&line, config, next_id);
    let mut out = serde_json::to_vec(&response).map_err(std::io::Error::other)?;
    out.push(b'\n');
    (&stream).write_all(&out)
}

/// Decides what to answer to one request line.
pub fn answer(line: &str, config: &TokenConfig, next_id: &AtomicU64) -> JoinResponse {
    let request: JoinRequest = match serde_json::from_str(line.trim()) {
        Ok(r) => r,
        Err(e) => return JoinResponse::Refused(format!("malformed join request: {e}")),
    };
    if request.code.trim().to_ascii_uppercase() != config.code {
        return JoinResponse::Refused("wrong join code".into());
    }
    if config.roles.is_taken(request.role) {
        return JoinResponse::Refused(format!("the {} role is already taken", request.role));
    }
    let now = SystemTime::now().duration_since(UNIX_EPOCH).unwrap_or_default();
    let client_id = next_id.fetch_add(1, Ordering::Relaxed);
    let user_data = TokenUserData { role: request.role, session: config.session }.encode();
    let token = ConnectToken::generate(
        now,
        PROTOCOL_ID,
        TOKEN_EXPIRE_S,
        client_id,
        TIMEOUT_S,
        vec![config.server_addr],
        Some(&user_data),
        &config.private_key,
    );
    match token {
        Ok(token) => {
            let mut bytes = Vec::new();
            match token.write(&mut bytes) {
                Ok(()) => JoinResponse::Token(bytes),
                Err(e) => JoinResponse::Refused(format!("could not encode the token: {e}")),
            }
        }
        Err(e) => JoinResponse::Refused(format!("could not mint a token: {e}")),
    }
}

/// A short human-friendly join code like `K7QX-2M4P`.
pub fn new_join_code() -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHJKLMNPQRSTUVWXYZ23456789";
    let mut s = String::with_capacity(9);
    for i in 0..8 {
        if i == 4 {
            s.push('-');
        }
        s.push(ALPHABET[rand::random_range(0..ALPHABET.len())] as char);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config() -> TokenConfig {
        TokenConfig {
            code: "ABCD-EFGH".into(),
            private_key: [7; 32],
            server_addr: "127.0.0.1:5000".parse().unwrap(),
            session: 42,
            roles: RoleTable::default(),
        }
    }

    #[test]
    fn a_right_code_gets_a_token_and_a_wrong_one_a_reason() {
        let ids = AtomicU64::new(1);
        let ok = answer(r#"{"code":"abcd-efgh","role":"Vive"}"#, &config(), &ids);
        let JoinResponse::Token(bytes) = ok else { panic!("no token: {ok:?}") };
        let token = ConnectToken::read(&mut bytes.as_slice()).expect("a readable token");
        assert_eq!(token.server_addresses[0], Some("127.0.0.1:5000".parse().unwrap()));
        let bad = answer(r#"{"code":"nope","role":"Vive"}"#, &config(), &ids);
        assert_eq!(bad, JoinResponse::Refused("wrong join code".into()));
        let junk = answer("\u{0}\u{1}garbage", &config(), &ids);
        assert!(matches!(junk, JoinResponse::Refused(r) if r.starts_with("malformed")));
    }

    #[test]
    fn a_taken_role_is_refused_at_the_door() {
        let c = config();
        c.roles.set(Role::Phantom, true);
        let r = answer(r#"{"code":"ABCD-EFGH","role":"Phantom"}"#, &c, &AtomicU64::new(1));
        assert_eq!(r, JoinResponse::Refused("the Phantom role is already taken".into()));
    }

    #[test]
    fn join_codes_look_right() {
        let c = new_join_code();
        assert_eq!(c.len(), 9);
        assert_eq!(&c[4..5], "-");
    }
}
