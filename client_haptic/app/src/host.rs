//! `client_haptic host`: a blind player hosts alone. The server runs in this process (on its own thread,
//! in real time) — or, with `--server ADDR`, the client creates a session on a running `heist-server
//! serve` — the client joins it as Phantom, and the join code to give the partner is said twice: as
//! written, and spelled slowly character by character in the NATO alphabet (R repeats it).

use std::net::SocketAddr;
use std::time::Duration;

use anyhow::Context as _;
use heist_shared::protocol::Role;

use crate::cli::HostArgs;
use crate::prompt::spell;

/// Runs `host`: starts the server, joins it as Phantom, says the code, plays until the session ends; a
/// failure to start is said as well as printed.
pub fn host(args: &HostArgs) -> anyhow::Result<()> {
    let mut settings = args.client.settings().map_err(anyhow::Error::msg)?;
    let mut prompter = crate::prompt::Prompter::new(&mut settings)?;
    crate::commands::check_device(&mut prompter, &settings)?;
    let started = match args.host.server {
        Some(server) => match heist_client::create_session(server, Role::Phantom, Duration::from_secs(5)) {
            Ok((code, token)) => Ok((server, server, code, token)),
            Err(e) => {
                prompter.say(format!("Could not create a heist on {server}. {}", crate::prompt::advice(&e).0));
                Err(anyhow::Error::new(e).context(format!("creating a session on {server}")))
            }
        },
        None => host_here(args).inspect_err(|e| {
            prompter.say(format!(
                "Could not host the heist: {e:#}. If another program uses port {}, choose another with --bind.",
                args.host.bind.port()
            ))
        }),
    };
    let (advertised, endpoint, code, token) = match started {
        Ok(s) => s,
        Err(e) => {
            prompter.finish_speaking(Duration::from_secs(30));
            return Err(e);
        }
    };
    let voices = prompter.into_parts();
    let mut app = crate::assemble::app(settings, args.client.headless, None, Some(voices))?;
    args.client.request_shot(&mut app);
    app.finish();
    app.cleanup();
    app.insert_resource(crate::client::HostedCode {
        intro: format!("You host the heist. Your partner joins at {advertised} with the code {code}."),
        spelled: format!("The code, spelled: {}. R repeats it.", spell(&code)),
    });
    heist_client::connect(&mut app, token)?;
    heist_client::hold_seat(&mut app, heist_client::SeatCache::in_default_dir(), endpoint, Role::Phantom);
    app.run();
    Ok(())
}

/// Starts the server in this process; returns its advertised address, its endpoint, the code and
/// Phantom's token.
fn host_here(args: &HostArgs) -> anyhow::Result<(SocketAddr, SocketAddr, String, heist_client::ConnectToken)> {
    let here = heist_server::embedded::start(args.host.options())?;
    let token = heist_client::request_token(here.endpoint, &here.code, Role::Phantom, Duration::from_secs(5))
        .with_context(|| format!("joining the session hosted on {}", here.endpoint))?;
    Ok((here.advertised, here.endpoint, here.code, token))
}
