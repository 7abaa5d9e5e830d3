//! Prediction under latency: the client's intents reach the server through a loopback relay that holds
//! every packet 150 ms each way (300 ms round trip); the body is predicted at once and reconciled with
//! each server state. The test walks a scripted course (turns, gait changes, into a wall) in real time
//! and measures how far the prediction for each input was from the server's position after that input.

mod common;

use std::time::{Duration, Instant};

use bevy::prelude::*;
use client_vr::intent::IntentSystems;
use client_vr::{Intent, ViveState};
use common::{join_args, quantile, vive_client};
use glam::Vec2;
use heist_bots::PhantomBotPlugin;
use heist_conditioner::{Conditions, Relay};
use heist_server::{ServerOptions, build_server, demo};
use heist_shared::protocol::{Gait, Phase, Role, TICK_HZ};

const LATENCY: Duration = Duration::from_millis(150);

/// The scripted course: seconds into the heist → direction and gait.
fn course(t: f32) -> (Vec2, Gait) {
    match t {
        t if t < 2.0 => (Vec2::new(1.0, 0.0), Gait::Walk),
        t if t < 4.0 => (Vec2::new(0.0, 1.0), Gait::Run),
        t if t < 6.0 => (Vec2::new((t * 2.0).cos(), (t * 2.0).sin()), Gait::Walk),
        t if t < 8.0 => (Vec2::new(-1.0, -0.3).normalize(), Gait::Run), // into the lobby's west wall
        t if t < 9.0 => (Vec2::ZERO, Gait::Walk),
        t if t < 11.0 => (Vec2::new(0.6, -0.8), Gait::Crouch),
        _ => (Vec2::new(1.0, 0.2).normalize(), Gait::Walk),
    }
}

#[derive(Resource, Default)]
struct Clock(f32);

fn drive(mut intent: ResMut<Intent>, state: Res<ViveState>, mut clock: ResMut<Clock>, time: Res<Time>) {
    if state.phase != Phase::Heist {
        return;
    }
    clock.0 += time.delta_secs();
    let (direction, gait) = course(clock.0);
    intent.movement = direction;
    intent.gait = gait;
}

/// What one run measured.
struct Measured {
    heist_ticks: u32,
    errors: Vec<f32>,
    acked: u32,
    max_error: f32,
    snaps: u32,
    pending: usize,
    ahead: Vec<f32>,
    walked_m: f32,
}

impl Measured {
    fn report(&self, name: &str) -> (f32, f32, f32) {
        let e = &self.errors;
        let (p50, p95, max) = (quantile(e, 0.5), quantile(e, 0.95), self.max_error);
        println!(
            "{name}: {} heist ticks, the server walked the body {:.1} m; prediction error at ack: p50 {p50:.4} m, p95 {p95:.4} m (last {} inputs), max {max:.4} m (all {} acknowledged); snaps {}; inputs in flight at the end {}; prediction ahead of the server's present p50 {:.3} m, max {:.3} m",
            self.heist_ticks,
            self.walked_m,
            e.len(),
            self.acked,
            self.snaps,
            self.pending,
            quantile(&self.ahead, 0.5),
            self.ahead.iter().copied().fold(0.0, f32::max),
        );
        (p50, p95, max)
    }
}

fn run(link: Conditions) -> Measured {
    let mut relay = Relay::bind(link, 0x9E37_79B9_7F4A_7C15).expect("the relay binds");
    let mut options = ServerOptions::local_test(10);
    options.advertise = Some(relay.addr);
    let mut server = build_server(options).expect("server starts");
    relay.start(server.addr).expect("the relay starts");
    let args = join_args(&["--headless", "--ready"]);
    let mut vive = vive_client(&server, &args, |app| {
        app.init_resource::<Clock>().add_systems(RunFixedMainLoop, drive.in_set(IntentSystems::Gather));
    });
    let mut phantom = demo::join(&server, Role::Phantom, |app| {
        app.add_plugins(PhantomBotPlugin::default());
    })
    .expect("Phantom bot joins");

    // Real time: the relay's delay is in wall-clock time, so each tick takes its 1/60 s.
    let period = Duration::from_secs_f64(1.0 / TICK_HZ);
    let started = Instant::now();
    let mut next = Instant::now();
    let mut m = Measured {
        heist_ticks: 0,
        errors: Vec::new(),
        acked: 0,
        max_error: 0.0,
        snaps: 0,
        pending: 0,
        ahead: Vec::new(),
        walked_m: 0.0,
    };
    let mut last = server.game().vive.position;
    while started.elapsed() < Duration::from_secs(40) && m.heist_ticks < 14 * 60 {
        server.update();
        vive.update();
        phantom.update();
        if server.game().phase == Phase::Heist {
            m.heist_ticks += 1;
            let now = server.game().vive.position;
            m.walked_m += now.distance(last);
            last = now;
            let state = vive.world().resource::<ViveState>();
            if let Some(p) = state.predictor.as_ref() {
                m.ahead.push(p.position().distance(now));
            }
        }
        next += period;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    let state = vive.world().resource::<ViveState>();
    let p = state.predictor.as_ref().expect("predicted");
    m.errors = p.errors.iter().copied().collect();
    m.acked = p.acked;
    m.max_error = p.max_error;
    m.snaps = p.snaps;
    m.pending = p.pending();
    m
}

#[test]
fn with_150_ms_each_way_the_prediction_matches_the_server() {
    let m = run(Conditions::delay(LATENCY));
    let (p50, p95, max) = m.report("150 ms each way");
    assert!(m.heist_ticks >= 12 * 60, "the heist ran long enough ({})", m.heist_ticks);
    assert!(m.walked_m > 15.0, "the server moved the body along the course ({} m)", m.walked_m);
    assert!(m.acked >= 600, "acknowledgements arrived ({})", m.acked);
    assert!(m.pending >= 10, "with 300 ms round trip about 18 inputs are in flight ({})", m.pending);
    assert!(p50 < 0.01 && p95 < 0.05 && max < 0.2, "prediction error p50 {p50} p95 {p95} max {max}");
    assert_eq!(m.snaps, 0, "no correction was big enough to snap");
    // Without prediction the view would lag the server by the round trip.
    assert!(quantile(&m.ahead, 0.5) > 0.1, "the prediction runs ahead of the server's present by the latency");
}

#[test]
fn with_150_ms_jitter_and_loss_reconciliation_keeps_the_prediction_close() {
    // 150 ms + up to 40 ms each way, 3 % of packets lost: the reliable channel resends, inputs arrive
    // bunched, the server moves some ticks on an older input — and the client must follow it.
    let m = run(Conditions { latency: LATENCY, jitter: Duration::from_millis(40), loss: 0.03 });
    let (p50, p95, max) = m.report("150 ms + 0–40 ms jitter, 3 % loss");
    assert!(m.heist_ticks >= 12 * 60, "the heist ran long enough ({})", m.heist_ticks);
    assert!(m.walked_m > 10.0, "the server moved the body along the course ({} m)", m.walked_m);
    assert!(m.acked >= 200, "acknowledgements arrived ({})", m.acked);
    assert!(p50 < 0.01 && p95 < 0.05 && max < 0.2, "prediction error p50 {p50} p95 {p95} max {max}");
    assert_eq!(m.snaps, 0, "no correction was big enough to snap");
}
