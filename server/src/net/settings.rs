//! The network side's settings: how clients prove who they are, the session registry, and what a
//! session created on request plays.

use bevy::prelude::*;

use super::registry::{Registry, SessionEntry};
use super::seats::Roles;
use crate::game::{Game, GameOptions};
use crate::session::{LogEcho, Session, SessionLog};

/// How clients prove who they are.
#[derive(Clone)]
pub enum Auth {
    /// Signed connect tokens from the token endpoint (the default).
    Secure {
        /// Netcode private key.
        private_key: [u8; 32],
    },
    /// Any client may claim any role: LAN development only.
    Insecure,
}

/// Network settings of the server.
#[derive(Resource, Clone)]
pub struct NetSettings {
    /// Authentication mode.
    pub auth: Auth,
    /// The sessions, shared with the token endpoint.
    pub registry: Registry,
    /// Which of the registry's shards this app plays.
    pub shard: usize,
    /// Refused messages (leaking one per second) tolerated per client before it is disconnected for abuse.
    pub abuse_limit: u32,
    /// The address put in tokens and checked in connection requests, when not the bound one.
    pub advertise: Option<std::net::SocketAddr>,
    /// What every session created on request plays: the level, and options whose seed is replaced by a
    /// fresh random one.
    pub new_sessions: NewSessions,
    /// Where refusals and resumes are counted.
    pub metrics: crate::fleet::Metrics,
}

/// What a session created on request plays.
#[derive(Clone)]
pub struct NewSessions {
    /// The level.
    pub level: heist_shared::level::Level,
    /// Options (time limit, idle end); each session draws its own seeds.
    pub game: GameOptions,
    /// Where its log goes.
    pub echo: LogEcho,
}

impl NewSessions {
    /// A session for `entry`: a fresh random seed (and random later rounds), unless `game` is given.
    pub fn session(&self, entry: &SessionEntry, game: Option<&GameOptions>) -> Session {
        let options = game.cloned().unwrap_or_else(|| GameOptions {
            seed: rand::random(),
            random_rounds: true,
            ends_unjoined: true,
            ..self.game.clone()
        });
        Session {
            id: entry.id,
            game: Game::new(self.level.clone(), &options),
            log: SessionLog {
                echo: self.echo,
                id: format!("{:08x}", rand::random::<u32>()),
                round: 1,
                ..Default::default()
            },
            roles: Roles::default(),
            seats: entry.seats.clone(),
            closed_at: None,
        }
    }
}
