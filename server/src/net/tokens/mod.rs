//! The token endpoint: a player who knows a session's join code gets a netcode connect token for their
//! role in it; a player may also create a new session (within the server's limits) and gets its code.
//!
//! TCP, on the game's port. Each connection runs the join exchange of [`heist_shared::protocol::join`]
//! (SPAKE2 keyed by the code: neither the code nor the token crosses the wire in clear) as its own task
//! on a small async runtime in its own thread, so no connection waits for another and the game loop
//! waits for none. Every connection has a deadline; connections are capped per address and in total (the
//! oldest gives way, so opening connections never locks anyone out); wrong codes are limited per address
//! and for the whole server ([`guesses`]).

mod connections;
mod exchange;
pub mod guesses;

use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime};

use heist_transport::limit::address_key;
use heist_transport::throttle::RefusalLog;

use super::registry::{CreateLimits, Registry};
use connections::Connections;
use guesses::{GuessLimits, Guesses};

/// A join code and when it stops working.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct JoinCode {
    /// The code, like `K7QX-2M4P-R9TC`.
    pub code: String,
    /// When it expires (wall clock).
    pub expires_at: SystemTime,
}

impl JoinCode {
    /// True once it has expired.
    pub fn is_expired(&self) -> bool {
        SystemTime::now() >= self.expires_at
    }

    /// "K7QX-2M4P-R9TC (expires 09:54:26 UTC, in 30 min)", for the host's terminal.
    pub fn describe(&self) -> String {
        let left = self.expires_at.duration_since(SystemTime::now()).unwrap_or_default();
        let at = self.expires_at.duration_since(SystemTime::UNIX_EPOCH).unwrap_or_default().as_secs() % 86_400;
        format!(
            "{} (expires {:02}:{:02}:{:02} UTC, in {} min)",
            self.code,
            at / 3600,
            at / 60 % 60,
            at % 60,
            left.as_secs().div_ceil(60)
        )
    }
}

/// A session's current join code, shared by the endpoint and the host, who can replace it. Every code
/// of the book starts with the session's room.
#[derive(Clone, Debug)]
pub struct CodeBook {
    current: Arc<Mutex<JoinCode>>,
    room: String,
    ttl: Duration,
}

impl CodeBook {
    /// A fresh code in `room` valid for `ttl`.
    pub fn new(room: &str, ttl: Duration) -> Self {
        Self { current: Arc::new(Mutex::new(Self::fresh(room, ttl))), room: room.to_owned(), ttl }
    }

    fn fresh(room: &str, ttl: Duration) -> JoinCode {
        JoinCode { code: format!("{room}-{}", new_secret()), expires_at: SystemTime::now() + ttl }
    }

    fn lock(&self) -> MutexGuard<'_, JoinCode> {
        self.current.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The code in force.
    pub fn current(&self) -> JoinCode {
        self.lock().clone()
    }

    /// Replaces the code with a fresh one (the old one stops working at once).
    pub fn rotate(&self) -> JoinCode {
        let fresh = Self::fresh(&self.room, self.ttl);
        *self.lock() = fresh.clone();
        fresh
    }
}

/// The endpoint's limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TokenLimits {
    /// Whole exchange, from accept to the last byte; default 2 s.
    pub deadline: Duration,
    /// Open connections per address (IPv6: per /64); default 32, the oldest gives way.
    pub per_address: usize,
    /// Open connections in all; default 256, the oldest gives way.
    pub total: usize,
    /// Wrong codes.
    pub guesses: GuessLimits,
    /// New sessions.
    pub creates: CreateLimits,
}

/// How many sessions a `serve` hosts at once unless told otherwise.
pub const DEFAULT_MAX_SESSIONS: usize = 96;

impl Default for TokenLimits {
    fn default() -> Self {
        Self {
            deadline: Duration::from_secs(2),
            per_address: 32,
            total: 256,
            guesses: GuessLimits::default(),
            creates: CreateLimits::default(),
        }
    }
}

/// What the endpoint needs to mint tokens.
#[derive(Clone)]
pub struct TokenConfig {
    /// The sessions, their codes and seats.
    pub registry: Registry,
    /// Netcode private key shared with the game server.
    pub private_key: [u8; 32],
    /// Each shard's public UDP address (must equal that shard's `public_addresses`): a session's tokens
    /// name its shard's.
    pub server_addrs: Vec<SocketAddr>,
    /// Limits.
    pub limits: TokenLimits,
    /// Where refusals are counted.
    pub metrics: crate::fleet::Metrics,
}

/// Everything the connection tasks share.
struct Shared {
    config: TokenConfig,
    started: Instant,
    guesses: Mutex<Guesses>,
    log: Mutex<RefusalLog>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl Shared {
    fn now_s(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    fn refused(&self, peer: SocketAddr, reason: &dyn std::fmt::Display) {
        lock(&self.log).refused(peer, reason, self.now_s());
    }
}

/// A running token endpoint; stops when dropped.
pub struct TokenService {
    /// Address it listens on.
    pub addr: SocketAddr,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl TokenService {
    /// Binds `bind` and serves on a background thread.
    pub fn spawn(bind: SocketAddr, config: TokenConfig) -> std::io::Result<Self> {
        let listener = std::net::TcpListener::bind(bind)?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let runtime = tokio::runtime::Builder::new_current_thread().enable_io().enable_time().build()?;
        let limits = config.limits;
        let shared = Arc::new(Shared {
            started: Instant::now(),
            guesses: Mutex::new(Guesses::new(limits.guesses)),
            log: Mutex::new(RefusalLog::new("heist_server::net::tokens", "token endpoint")),
            config,
        });
        let (stop, stopped) = tokio::sync::oneshot::channel();
        let thread = std::thread::Builder::new().name("token-endpoint".into()).spawn(move || {
            runtime.block_on(async move {
                match tokio::net::TcpListener::from_std(listener) {
                    Ok(listener) => accept(listener, shared, stopped).await,
                    Err(e) => log::error!("token endpoint: cannot serve on {addr}: {e}"),
                }
            });
        })?;
        Ok(Self { addr, stop: Some(stop), thread: Some(thread) })
    }
}

impl Drop for TokenService {
    fn drop(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Accepts connections until told to stop; each becomes its own task.
async fn accept(listener: tokio::net::TcpListener, shared: Arc<Shared>, mut stop: tokio::sync::oneshot::Receiver<()>) {
    let limits = shared.config.limits;
    let open = Arc::new(Mutex::new(Connections::new(limits.per_address, limits.total)));
    loop {
        let accepted = tokio::select! {
            _ = &mut stop => break,
            accepted = listener.accept() => accepted,
        };
        let (stream, peer) = match accepted {
            Ok(a) => a,
            Err(e) => {
                // Out of descriptors, usually: back off instead of spinning.
                log::warn!("token endpoint: accept failed: {e}");
                tokio::time::sleep(Duration::from_millis(50)).await;
                continue;
            }
        };
        let key = address_key(peer.ip());
        let id = lock(&open).next_id();
        let task = tokio::spawn(exchange::serve(stream, peer, shared.clone(), Closer { open: open.clone(), id }));
        // The task has not run yet (one thread): registering now cannot miss its end.
        for pushed_out in lock(&open).open(id, key, task.abort_handle()) {
            pushed_out.abort();
        }
    }
}

/// Removes a connection from the open set when its task ends, however it ends.
struct Closer {
    open: Arc<Mutex<Connections<tokio::task::AbortHandle>>>,
    id: u64,
}

impl Drop for Closer {
    fn drop(&mut self) {
        lock(&self.open).close(self.id);
    }
}

/// Letters of join codes: no 0/O, 1/I to mix up.
const ALPHABET: &[u8] = b"ABCDEFGHJKLMNPQRSTUVWXYZ23456789";

fn letters(n: usize) -> impl Iterator<Item = char> {
    (0..n).map(|_| ALPHABET[rand::random_range(0..ALPHABET.len())] as char)
}

/// A fresh room: the public first group of a session's codes, like `K7QX` (20 bits; unique among the
/// open sessions).
pub fn new_room() -> String {
    letters(4).collect()
}

/// The secret part of a join code, like `2M4P-R9TC` (40 bits: 32⁸).
fn new_secret() -> String {
    let mut s: String = letters(4).collect();
    s.push('-');
    s.extend(letters(4));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn join_codes_look_right() {
        let c = CodeBook::new("K7QX", Duration::from_secs(60)).current().code;
        assert_eq!(c.len(), 14, "{c}");
        assert!(c.starts_with("K7QX-") && &c[9..10] == "-", "{c}");
        assert_eq!(heist_shared::protocol::join::room_of(&c).as_deref(), Ok("K7QX"));
    }

    #[test]
    fn a_rotated_code_replaces_the_old_one_and_expires_later() {
        let book = CodeBook::new("ROOM", Duration::from_secs(60));
        let first = book.current();
        assert!(!first.is_expired());
        assert!(first.describe().contains("in 1 min"), "{}", first.describe());
        let second = book.rotate();
        assert_ne!(second.code, first.code);
        assert_eq!(book.current(), second);
        assert!(second.code.starts_with("ROOM-"), "a rotated code stays in its room");
        assert!(CodeBook::new("ROOM", Duration::ZERO).current().is_expired());
    }
}
