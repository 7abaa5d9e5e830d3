//! Bot pairs for a load: each creates a session through the token endpoint (Vive creates it, Phantom
//! joins with its code), and a bot client alone that takes its seat back (the churn's comebacks).

use std::time::Duration;

use anyhow::Context as _;
use bevy::prelude::*;
use heist_bots::{PhantomBotPlugin, Rounds, ViveBotPlugin, ViveStyle};
use heist_shared::protocol::{Role, SeatTicket};

use crate::HostedServer;

/// How long each exchange with the token endpoint may take.
const TOKEN_TIMEOUT: Duration = Duration::from_secs(5);

/// A bot pair in a session it created: Vive creates it, Phantom joins with its code; `probe` adds a
/// test's systems to both apps.
pub fn create_bot_pair(
    server: &HostedServer,
    style: ViveStyle,
    rounds: u32,
    probe: impl Fn(&mut App),
) -> anyhow::Result<[App; 2]> {
    let endpoint = server.tokens.as_ref().context("the server runs without a token endpoint")?.addr;
    create_bot_pair_at(endpoint, style, rounds, probe)
}

/// [`create_bot_pair`] through the token endpoint at `endpoint`.
pub fn create_bot_pair_at(
    endpoint: std::net::SocketAddr,
    style: ViveStyle,
    rounds: u32,
    probe: impl Fn(&mut App),
) -> anyhow::Result<[App; 2]> {
    let (code, token) = heist_client::create_session(endpoint, Role::Vive, TOKEN_TIMEOUT)?;
    let vive = bot_app(token, Role::Vive, style, rounds, &probe)?;
    let token = heist_client::request_token(endpoint, &code, Role::Phantom, TOKEN_TIMEOUT)?;
    let phantom = bot_app(token, Role::Phantom, style, rounds, &probe)?;
    Ok([vive, phantom])
}

/// A bot client of `role` that takes its kept seat back with `ticket` through the token endpoint at
/// `endpoint` (the resume exchange), and plays on for every round.
pub(super) fn resumed_bot(
    endpoint: std::net::SocketAddr,
    role: Role,
    ticket: &SeatTicket,
    style: ViveStyle,
) -> anyhow::Result<App> {
    let token = heist_client::request_resume_token(endpoint, role, ticket, TOKEN_TIMEOUT)?;
    bot_app(token, role, style, u32::MAX, |_| {})
}

/// A bot client of `role` connecting with `token`, playing `rounds` rounds; `probe` adds a test's systems.
fn bot_app(
    token: heist_client::ConnectToken,
    role: Role,
    style: ViveStyle,
    rounds: u32,
    probe: impl Fn(&mut App),
) -> anyhow::Result<App> {
    crate::demo::client_with_token(token, |app| {
        match role {
            Role::Vive => app.add_plugins(ViveBotPlugin { style }),
            Role::Phantom => app.add_plugins(PhantomBotPlugin::default()),
        };
        app.insert_resource(Rounds(rounds));
        probe(app);
    })
}
