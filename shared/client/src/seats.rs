//! The seat cache: a client keeps the seat ticket of the session it plays in its cache directory, so a
//! player whose client was killed, crashed or lost the network takes their seat back by joining again
//! (within the server's hold time) instead of being refused or starting anew. One file per server
//! address and role, readable by its owner only; removed when the session is over for us.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use bevy::prelude::*;
use heist_shared::protocol::join::JoinRefusal;
use heist_shared::protocol::{DisconnectReason, Role, SeatTicket};
use heist_transport::renetcode::ConnectToken;

use crate::{Inbox, JoinError, Leaving};

/// Where seat tickets are kept.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SeatCache {
    dir: PathBuf,
}

impl SeatCache {
    /// A cache in `dir` (created when the first ticket is stored).
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into() }
    }

    /// `$XDG_CACHE_HOME/phantom-heist/seats` (or `~/.cache/…`); `None` when neither is set.
    pub fn default_dir() -> Option<PathBuf> {
        let base = std::env::var_os("XDG_CACHE_HOME")
            .filter(|d| !d.is_empty())
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
        Some(base.join("phantom-heist").join("seats"))
    }

    /// The cache in [`SeatCache::default_dir`], if there is one.
    pub fn in_default_dir() -> Option<Self> {
        Self::default_dir().map(Self::new)
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    fn file(&self, server: SocketAddr, role: Role) -> PathBuf {
        let host: String =
            server.ip().to_string().chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
        self.dir.join(format!("{host}-{}-{}.seat", server.port(), role.name()))
    }

    /// The ticket kept for `role` at `server`; `None` when there is none (a damaged file is removed, with a
    /// warning).
    pub fn load(&self, server: SocketAddr, role: Role) -> Option<SeatTicket> {
        let file = self.file(server, role);
        let text = std::fs::read_to_string(&file).ok()?;
        match SeatTicket::from_hex(&text) {
            Ok(ticket) => Some(ticket),
            Err(e) => {
                warn!("ignoring the damaged seat ticket {}: {e}", file.display());
                let _ = std::fs::remove_file(&file);
                None
            }
        }
    }

    /// Keeps `ticket` for `role` at `server` (written whole, then renamed into place).
    pub fn store(&self, server: SocketAddr, role: Role, ticket: &SeatTicket) -> std::io::Result<()> {
        std::fs::create_dir_all(&self.dir)?;
        let file = self.file(server, role);
        let tmp = file.with_extension("seat.tmp");
        write_private(&tmp, ticket.to_hex().as_bytes())?;
        std::fs::rename(&tmp, &file)
    }

    /// Forgets the ticket for `role` at `server` (nothing to forget is fine).
    pub fn forget(&self, server: SocketAddr, role: Role) {
        let _ = std::fs::remove_file(self.file(server, role));
    }
}

#[cfg(unix)]
fn write_private(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write as _;
    use std::os::unix::fs::OpenOptionsExt as _;
    let mut f = std::fs::OpenOptions::new().write(true).create(true).truncate(true).mode(0o600).open(path)?;
    f.write_all(bytes)
}

#[cfg(not(unix))]
fn write_private(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    std::fs::write(path, bytes)
}

/// A connect token and how it was had.
pub struct Joining {
    /// The token.
    pub token: ConnectToken,
    /// True when it takes a kept seat back (the cache had its ticket).
    pub resuming: bool,
}

/// Joins `endpoint` as `role`: with the seat ticket in `cache`, if one is kept for that server and role,
/// taking the seat back; otherwise (or when the server has no such seat any more) with `code`.
pub fn join_or_resume(
    endpoint: SocketAddr,
    code: &str,
    role: Role,
    cache: Option<&SeatCache>,
    timeout: Duration,
) -> Result<Joining, JoinError> {
    if let Some((cache, ticket)) = cache.and_then(|c| c.load(endpoint, role).map(|t| (c, t))) {
        match crate::token::request_resume_token(endpoint, role, &ticket, timeout) {
            Ok(token) => return Ok(Joining { token, resuming: true }),
            Err(JoinError::Refused(JoinRefusal::NoSeat(_) | JoinRefusal::WrongTicket)) => {
                info!("the kept {role} seat at {endpoint} is gone: joining with the code");
                cache.forget(endpoint, role);
            }
            Err(e) => return Err(e),
        }
    }
    let token = crate::token::request_token(endpoint, code, role, timeout)?;
    Ok(Joining { token, resuming: false })
}

/// The seat this client plays, kept in its cache while the session lasts ([`hold_seat`] inserts it).
#[derive(Resource, Clone, Debug)]
pub struct SeatKeeper {
    /// The cache.
    pub cache: SeatCache,
    /// The server's address (the token endpoint's).
    pub server: SocketAddr,
    /// Our role.
    pub role: Role,
}

/// The client holds on to its seat at `server` (the token endpoint) as `role` (call after connecting):
/// it keeps each welcome's ticket in `cache` (when there is one), for a restarted client, and takes the
/// seat back by itself after a lost connection ([`crate::Rejoin`]).
pub fn hold_seat(app: &mut App, cache: Option<SeatCache>, server: SocketAddr, role: Role) {
    if let Some(cache) = cache {
        app.insert_resource(SeatKeeper { cache, server, role });
    }
    app.insert_resource(crate::Rejoin::new(server, role));
}

/// Stores the ticket of each welcome, and forgets it once the session is over for us: it ended, we left,
/// or the server turned the seat down. (A lost connection keeps it: that is what it is for.)
pub(crate) fn keep_seat(
    keeper: Option<Res<SeatKeeper>>,
    inbox: Res<Inbox>,
    leaving: Res<Leaving>,
    mut stored: Local<u32>,
    mut forgotten: Local<bool>,
) {
    let Some(keeper) = keeper else { return };
    if *forgotten {
        return;
    }
    let over = leaving.since.is_some()
        || matches!(
            inbox.disconnect,
            Some(DisconnectReason::SessionEnded | DisconnectReason::BadSeat | DisconnectReason::Abuse)
        );
    if over {
        keeper.cache.forget(keeper.server, keeper.role);
        *forgotten = true;
        return;
    }
    if inbox.received.welcome != *stored {
        *stored = inbox.received.welcome;
        if let Some(ticket) = inbox.seat
            && let Err(e) = keeper.cache.store(keeper.server, keeper.role, &ticket)
        {
            warn!("could not keep the seat ticket in {}: {e}", keeper.cache.dir().display());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ticket_is_kept_per_server_and_role_and_a_damaged_one_is_dropped() {
        let dir = std::env::temp_dir().join(format!("heist-seats-{}", std::process::id()));
        let cache = SeatCache::new(&dir);
        let (a, b): (SocketAddr, SocketAddr) = ("127.0.0.1:7000".parse().unwrap(), "[::1]:7000".parse().unwrap());
        let t = SeatTicket::random();
        assert_eq!(cache.load(a, Role::Vive), None);
        cache.store(a, Role::Vive, &t).unwrap();
        assert_eq!(cache.load(a, Role::Vive), Some(t));
        assert_eq!(cache.load(a, Role::Phantom), None, "another role");
        assert_eq!(cache.load(b, Role::Vive), None, "another server");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt as _;
            let mode = std::fs::metadata(cache.file(a, Role::Vive)).unwrap().permissions().mode();
            assert_eq!(mode & 0o077, 0, "only its owner reads a ticket");
        }
        std::fs::write(cache.file(b, Role::Vive), "not a ticket").unwrap();
        assert_eq!(cache.load(b, Role::Vive), None);
        assert!(!cache.file(b, Role::Vive).exists(), "the damaged file is removed");
        cache.forget(a, Role::Vive);
        assert_eq!(cache.load(a, Role::Vive), None);
        let _ = std::fs::remove_dir_all(dir);
    }
}
