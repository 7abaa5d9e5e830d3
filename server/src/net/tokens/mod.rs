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
mod shared;

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use heist_transport::limit::address_key;
use heist_transport::throttle::RefusalLog;

pub use super::codes::{CodeBook, JoinCode, new_room};
use connections::Connections;
use guesses::Guesses;
use shared::{Closer, Shared, lock};
pub use shared::{DEFAULT_MAX_SESSIONS, TokenConfig, TokenLimits};

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
