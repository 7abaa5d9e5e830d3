//! End to end: the real server, this client in bot mode (`--headless --bot`: the Vive bot's brain
//! driving intents, prediction and reconciliation) and a Phantom bot win a heist over loopback UDP.

mod common;

use bevy::prelude::*;
use client_vr::client::PulseReason;
use client_vr::interp::Track;
use client_vr::{Action, ViveState};
use common::{join_args, quantile, vive_client};
use heist_bots::PhantomBotPlugin;
use heist_server::{ServerOptions, build_server, demo};
use heist_shared::protocol::{ClientMsg, GuardView, PhantomMsg, PhantomTool, Phase, Role, SessionView, TICK_HZ};

/// The Phantom bot does not touch anything; this moves its tool in a circle over the bench, as the
/// Phantom client reports its stylus.
fn wave_the_tool(mut out: MessageWriter<ClientMsg>, session: Query<&SessionView>, mut t: Local<f32>) {
    if session.iter().next().is_none_or(|s| s.phase != Phase::Heist) {
        return;
    }
    *t += 1.0 / 60.0;
    let position = Vec3::new(0.1 * t.cos(), 0.05, 0.1 * t.sin());
    out.write(ClientMsg::Phantom(PhantomMsg::ToolPose { position, rotation: Quat::from_rotation_y(*t) }));
}

#[test]
fn the_vive_client_in_bot_mode_and_a_phantom_bot_win_a_heist() {
    let seed = 2;
    let mut options = ServerOptions::local_test(seed);
    options.game.difficulty = heist_shared::rules::Difficulty::Easy;
    let mut server = build_server(options).expect("server starts");
    let args = join_args(&["--headless", "--bot"]);
    let mut vive = vive_client(&server, &args, |_| {});
    let mut phantom = demo::join(&server, Role::Phantom, |app| {
        app.add_plugins(PhantomBotPlugin::default()).add_systems(Update, wave_the_tool);
    })
    .expect("Phantom bot joins");
    let limit = server.game().time_left_s;
    let max_ticks = ((f64::from(limit) + 40.0) * TICK_HZ) as u64;
    let mut ticks = 0;
    // Every second: (snapshots kept per guard tracked, guards held) — only the guards Vive perceives are
    // sent to his client, so at the end of a heist there may be none in view.
    let mut samples: Vec<(Vec<usize>, usize)> = Vec::new();
    while ticks < max_ticks {
        server.update();
        vive.update();
        phantom.update();
        ticks += 1;
        if ticks % TICK_HZ as u64 == 0 {
            let world = vive.world_mut();
            let guards: Vec<usize> = world.query::<(&GuardView, &Track)>().iter(world).map(|(_, t)| t.len()).collect();
            let held = world.query::<&GuardView>().iter(world).count();
            samples.push((guards, held));
        }
        if !server.game().is_running() && server.game().phase != Phase::Lobby {
            for _ in 0..10 {
                server.update();
                vive.update();
                phantom.update();
            }
            break;
        }
    }
    // What the server moves arrives as snapshots to interpolate: the guards, and the Phantom's tool.
    let world = vive.world_mut();
    let tool: Vec<(usize, Vec3)> = world
        .query::<(&PhantomTool, &Track)>()
        .iter(world)
        .map(|(_, t)| (t.len(), t.latest().map_or(Vec3::ZERO, |s| s.position)))
        .collect();
    let in_view: Vec<&(Vec<usize>, usize)> = samples.iter().filter(|(_, held)| *held > 0).collect();
    println!("snapshots kept per guard, each second a guard was in view: {in_view:?}; tool {tool:?}");
    // Only the guards Vive perceives are sent to his client (interest management): each one held is tracked.
    assert!(!in_view.is_empty(), "guards came into view during the heist");
    assert!(samples.iter().all(|(g, held)| g.len() == *held), "every guard held is tracked: {samples:?}");
    assert!(
        in_view.iter().any(|(g, _)| g.iter().all(|n| *n >= 2)),
        "guards have snapshots to interpolate between: {in_view:?}"
    );
    assert!(tool.len() == 1 && tool[0].0 >= 2, "the Phantom's tool moves as reported");
    let game = server.game();
    let state = vive.world().resource::<ViveState>();
    let predictor = state.predictor.as_ref().expect("the client predicted");
    let errors: Vec<f32> = predictor.errors.iter().copied().collect();
    let sent = vive.world().resource::<client_vr::intent::Sent>();
    println!(
        "seed {seed}: {:?} after {:.1} s of game time; {} moves sent, actions {:?}",
        game.phase, game.elapsed_s, sent.seq, sent.actions
    );
    println!(
        "reconciliations {}, prediction error at ack: p50 {:.4} m, p99 {:.4} m (last {}), max {:.4} m (all {} acks); pulses {:?}",
        state.reconciliations,
        quantile(&errors, 0.5),
        quantile(&errors, 0.99),
        errors.len(),
        predictor.max_error,
        predictor.acked,
        state.pulses
    );
    for line in server.log().iter().rev().take(8).rev() {
        println!("  server: {line}");
    }
    assert_eq!(game.phase, Phase::Won, "the heist was won");
    assert_eq!(state.phase, Phase::Won, "the client saw the win");
    assert!(sent.actions.iter().any(|a| matches!(a, Action::Place(_))), "copies went to the workbench through intents");
    assert!(sent.actions.iter().any(|a| matches!(a, Action::Break(_))), "cases were broken through intents");
    assert!(state.reconciliations > 1000, "the server's state reconciled the prediction");
    assert!(state.pulses.contains(&PulseReason::Grab), "a grab pulses the controller");
    assert!(state.pulses.contains(&PulseReason::Glass), "breaking glass pulses the controller");
    // Nearly every tick of the heist's moves was acknowledged (60 a second), each agreeing with the server.
    let ticks = f64::from(game.elapsed_s) * TICK_HZ;
    assert!(predictor.acked as f64 > 0.8 * ticks, "{} acks in {ticks:.0} ticks", predictor.acked);
    assert!(predictor.max_error < 0.01, "prediction agreed with the server at every ack");
}

#[test]
fn the_vive_client_in_bot_mode_and_a_phantom_bot_win_a_heist_over_a_poor_link() {
    use heist_conditioner::{Conditions, SteppedRelay};
    // Both clients reach the server through lightyear's "poor" link, each way: 200 ms, 30 ms jitter,
    // 10 % loss. The relay steps with the apps, so the latency is in game time and the run repeats.
    // Seed 3 on easy is one the bots win over this link (they see guards a round trip late and are
    // caught on many; docs/vive-client.md "Figures" has the sweep, run with HEIST_POOR_SEED).
    let seed: u64 = std::env::var("HEIST_POOR_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(3);
    let mut relay = SteppedRelay::bind(Conditions::POOR, seed).expect("the relay binds");
    let mut options = ServerOptions::local_test(seed);
    options.game.difficulty = heist_shared::rules::Difficulty::Easy;
    options.advertise = Some(relay.addr());
    let mut server = build_server(options).expect("server starts");
    relay.forward_to(server.addr);
    let args = join_args(&["--headless", "--bot"]);
    let mut vive = vive_client(&server, &args, |_| {});
    let mut phantom = demo::join(&server, Role::Phantom, |app| {
        app.add_plugins(PhantomBotPlugin::default());
    })
    .expect("Phantom bot joins");
    let tick = std::time::Duration::from_secs_f64(1.0 / TICK_HZ);
    let limit = server.game().time_left_s;
    let max_ticks = ((f64::from(limit) + 40.0) * TICK_HZ) as u64;
    for _ in 0..max_ticks {
        server.update();
        vive.update();
        phantom.update();
        relay.advance(tick).expect("the relay runs");
        if !server.game().is_running() && server.game().phase != Phase::Lobby {
            break;
        }
    }
    let game = server.game();
    let state = vive.world().resource::<ViveState>();
    let predictor = state.predictor.as_ref().expect("the client predicted");
    let errors: Vec<f32> = predictor.errors.iter().copied().collect();
    let traffic = relay.stats();
    println!(
        "poor link, seed {seed}: {:?} after {:.1} s of game time; prediction error at ack p50 {:.4} m, p99 {:.4} m, max {:.4} m ({} acks, {} reconciliations); datagrams lost up {} of {}, down {} of {}",
        game.phase,
        game.elapsed_s,
        quantile(&errors, 0.5),
        quantile(&errors, 0.99),
        predictor.max_error,
        predictor.acked,
        state.reconciliations,
        traffic.up.dropped,
        traffic.up.dropped + traffic.up.passed,
        traffic.down.dropped,
        traffic.down.dropped + traffic.down.passed,
    );
    for line in server.log().iter().rev().take(8).rev() {
        println!("  server: {line}");
    }
    assert_eq!(game.phase, Phase::Won, "the heist was won over the poor link");
    let lost = |t: heist_conditioner::Traffic| t.dropped as f64 / (t.dropped + t.passed).max(1) as f64;
    assert!((0.08..=0.12).contains(&lost(traffic.up)), "about a tenth lost upstream: {traffic:?}");
    assert!((0.08..=0.12).contains(&lost(traffic.down)), "and downstream: {traffic:?}");
    let ticks = game.elapsed_s * TICK_HZ as f32;
    assert!(
        predictor.acked as f32 > ticks / 3.0,
        "the server's acks kept coming: {} in {ticks} ticks",
        predictor.acked
    );
    assert!(predictor.max_error < 0.05, "the prediction held within 5 cm at every ack: {}", predictor.max_error);
}
