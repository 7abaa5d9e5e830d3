//! Shared helpers for the end-to-end tests: a server and hand-driven clients over loopback UDP.
//!
//! Every loop here is bounded by a tick count; the clock is stepped by hand (1/60 s per update), so a
//! test's outcome does not depend on the machine's speed.

use bevy::prelude::*;
use heist_client::Inbox;
pub use heist_server::demo::{Heist, join};
use heist_server::{HostedServer, ServerOptions, build_server};
use heist_shared::protocol::{Phase, Role, SessionView};
pub use heist_transport::renetcode::ConnectToken;

/// Ticks per second of game time.
pub const HZ: u64 = 60;

/// A server with hand-driven clients.
pub struct Session {
    /// The server.
    pub server: HostedServer,
    /// Clients, in join order.
    pub clients: Vec<App>,
}

impl Session {
    /// A secure loopback server with the museum and `seed`.
    pub fn new(seed: u64) -> Self {
        Self::with_options(ServerOptions::local_test(seed))
    }

    /// A server with the given options.
    pub fn with_options(options: ServerOptions) -> Self {
        let server = build_server(options).expect("server starts");
        Self { server, clients: Vec::new() }
    }

    /// Joins a client with `role` (through the token endpoint); returns its index.
    pub fn join(&mut self, role: Role, setup: impl FnOnce(&mut App)) -> usize {
        let app = join(&self.server, role, setup).expect("client joins");
        self.clients.push(app);
        self.clients.len() - 1
    }

    /// One tick for the server and every client.
    pub fn step(&mut self) {
        self.server.update();
        for c in &mut self.clients {
            c.update();
        }
    }

    /// Steps until `done` holds, at most `max_ticks`; returns whether it held.
    pub fn step_until(&mut self, max_ticks: u64, mut done: impl FnMut(&Self) -> bool) -> bool {
        for _ in 0..max_ticks {
            self.step();
            if done(self) {
                return true;
            }
        }
        false
    }

    /// A client's inbox.
    pub fn inbox(&self, client: usize) -> &Inbox {
        self.clients[client].world().resource::<Inbox>()
    }

    /// The session phase as a client sees it (None before replication arrives).
    pub fn client_phase(&mut self, client: usize) -> Option<Phase> {
        let world = self.clients[client].world_mut();
        world.query::<&SessionView>().iter(world).next().map(|s| s.phase)
    }

    /// Sends a message from a client (written as a Bevy message; the client core sends it).
    pub fn send(&mut self, client: usize, msg: heist_shared::protocol::ClientMsg) {
        self.clients[client].world_mut().write_message(msg);
    }
}

/// A local test server on `seed` at the easy difficulty: the one the careful Vive bot wins most often
/// (docs/rules.md, "Bot status"). Tests of the network, seats and attacks that need a whole heist won
/// use it with a seed the bots win (deterministic: stepped clock, loopback UDP).
pub fn easy(seed: u64) -> ServerOptions {
    let mut options = ServerOptions::local_test(seed);
    options.game.difficulty = heist_shared::rules::Difficulty::Easy;
    options
}

/// Runs a whole bot heist and returns the final phase and the log.
pub fn bot_heist(options: ServerOptions, style: heist_bots::ViveStyle, max_game_s: f32) -> (Phase, Vec<String>, f32) {
    let mut heist = Heist::start(options, style).expect("heist starts");
    let phase = heist.run(max_game_s);
    let game = heist.server.game();
    (phase, heist.server.log().to_vec(), game.elapsed_s)
}

/// An attacker on the network with a real connect token: a bare netcode client over its own UDP socket,
/// with no checks, sending whatever the test tells it to.
pub struct UdpAttacker {
    /// Its socket.
    pub socket: std::net::UdpSocket,
    /// Its netcode state.
    pub netcode: heist_transport::renetcode::NetcodeClient,
    /// The server's game address.
    pub server: std::net::SocketAddr,
}

impl UdpAttacker {
    /// An attacker holding `token`; it has sent nothing yet.
    pub fn new(token: heist_transport::renetcode::ConnectToken) -> Self {
        let server = token.server_addresses[0].expect("the token names the server");
        let socket = std::net::UdpSocket::bind("127.0.0.1:0").expect("a loopback socket");
        socket.set_nonblocking(true).expect("non-blocking");
        let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
        let auth = heist_transport::renetcode::ClientAuthentication::Secure { connect_token: token };
        let netcode = heist_transport::renetcode::NetcodeClient::new(now, auth).expect("netcode starts");
        Self { socket, netcode, server }
    }

    /// Reads what the server sent and sends netcode's next handshake or keep-alive packet.
    pub fn pump(&mut self) {
        let mut buf = [0u8; 1500];
        while let Ok((len, _)) = self.socket.recv_from(&mut buf) {
            let _ = self.netcode.process_packet(&mut buf[..len]);
        }
        if let Some((packet, to)) = self.netcode.update(std::time::Duration::from_secs_f64(1.0 / 60.0)) {
            let _ = self.socket.send_to(packet, to);
        }
    }

    /// Sends raw bytes to the server.
    pub fn send_raw(&self, bytes: &[u8]) {
        self.socket.send_to(bytes, self.server).expect("loopback send");
    }

    /// Seals `packet`, alone in a bundle (heist_transport::bundle), with the session key (once connected)
    /// and sends it.
    pub fn send_sealed(&mut self, packet: &[u8]) {
        let bundle = heist_transport::bundle::single(packet);
        if let Ok((to, bytes)) = self.netcode.generate_payload_packet(&bundle) {
            let _ = self.socket.send_to(bytes, to);
        }
    }

    /// Tells the server it leaves.
    pub fn leave(&mut self) {
        if let Ok((to, bytes)) = self.netcode.disconnect() {
            let _ = self.socket.send_to(bytes, to);
        }
    }
}

/// A token for `role` from `server`'s endpoint, as any holder of the join code gets one.
pub fn token_for(server: &HostedServer, role: Role) -> ConnectToken {
    heist_server::demo::token(server, role).expect("a token")
}

/// A seat cache of its own for one test client (a fresh directory under the system's temp dir).
pub fn seat_cache(name: &str) -> heist_client::SeatCache {
    let dir = std::env::temp_dir().join(format!("heist-seats-{}-{name}-{}", std::process::id(), rand::random::<u32>()));
    heist_client::SeatCache::new(dir)
}

/// Joins `server` as `role` like a player's client does: with the seat ticket kept in `cache` when there
/// is one (taking the seat back), else with the join code; the client keeps its seat in `cache`. Returns
/// the app and whether it took a seat back.
pub fn join_with_seat(
    server: &HostedServer,
    role: Role,
    cache: &heist_client::SeatCache,
    setup: impl FnOnce(&mut App),
) -> Result<(App, bool), heist_client::JoinError> {
    let tokens = server.tokens.as_ref().expect("a token endpoint");
    let code = server.join_code().expect("a host session").code;
    let timeout = std::time::Duration::from_secs(5);
    let joining = heist_client::join_or_resume(tokens.addr, &code, role, Some(cache), timeout)?;
    let mut app = heist_server::demo::stepped_client_app();
    setup(&mut app);
    app.finish();
    app.cleanup();
    heist_client::connect(&mut app, joining.token)?;
    heist_client::hold_seat(&mut app, Some(cache.clone()), tokens.addr, role);
    Ok((app, joining.resuming))
}
