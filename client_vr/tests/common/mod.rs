//! Helpers for the Vive client's tests: a stepped client app joined to a test server (the link
//! conditioner is `heist_conditioner`).
#![allow(dead_code)]

use std::time::Duration;

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use clap::Parser as _;
use client_vr::cli::{Cli, Command, JoinArgs, Mode};
use heist_server::HostedServer;
use heist_shared::protocol::{Role, TICK_HZ};

/// Parses `client_vr join … EXTRA` arguments.
pub fn join_args(extra: &[&str]) -> JoinArgs {
    let mut argv = vec!["client_vr", "join", "127.0.0.1:1", "--code", "X"];
    argv.extend_from_slice(extra);
    match Cli::try_parse_from(argv).expect("arguments parse").command {
        Command::Join(a) => a,
        _ => unreachable!(),
    }
}

/// The real headless Vive client app, joined to `server` through its token endpoint, its clock stepped
/// one tick per update; `setup` adds test systems before it connects.
pub fn vive_client(server: &HostedServer, args: &JoinArgs, setup: impl FnOnce(&mut App)) -> App {
    let token = heist_server::demo::token(server, Role::Vive).expect("token");
    let mut app = client_vr::cli::app(&args.vive, &Mode::Headless).expect("the app builds");
    app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(1.0 / TICK_HZ)));
    setup(&mut app);
    app.finish();
    app.cleanup();
    heist_client::connect(&mut app, token).expect("connects");
    app
}

/// The `q`-quantile of `values` (sorted copy).
pub fn quantile(values: &[f32], q: f32) -> f32 {
    if values.is_empty() {
        return f32::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f32 * q).round() as usize]
}
