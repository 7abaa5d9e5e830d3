//! The server on a fleet, in-process: what it tells an Agones sidecar (a fake one speaking the SDK's
//! gRPC protocol, generated from the agones crate's .proto files) as sessions come and go, when the
//! game loop stalls, and through a drain.

#![allow(clippy::unwrap_used)] // helpers outside the #[test] fns unwrap too: a panic fails the test

use std::time::{Duration, Instant};

use agones_fake::{Declared, FakeAgones, Recorded};
use bevy::prelude::*;
use heist_bots::ViveStyle;
use heist_server::build_server;
use heist_server::fleet::agones::{AgonesOptions, GameServerInfo, PLAYERS_LIST, SESSIONS_COUNTER};
use heist_server::fleet::{FleetOptions, FleetServices};
use heist_server::load::{create_bot_pair, load_server_options};

/// Steps the server and `clients` (one tick each, a few ms of wall clock apart, as a running server
/// would) until `done` holds for what the sidecar recorded, at most `limit`; true if it did.
fn run_until(
    server: &mut heist_server::HostedServer,
    clients: &mut [App],
    fake: &FakeAgones,
    limit: Duration,
    done: impl Fn(&Recorded) -> bool,
) -> bool {
    let deadline = Instant::now() + limit;
    while Instant::now() < deadline {
        server.update();
        clients.iter_mut().for_each(App::update);
        if done(&fake.recorded()) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(3));
    }
    false
}

#[test]
fn agones_hears_ready_health_the_sessions_counter_players_list_a_stall_and_shutdown_after_a_drain() {
    let declared = Declared {
        counters: vec![(SESSIONS_COUNTER.into(), 1000)],
        lists: vec![(PLAYERS_LIST.into(), 1000)],
        ports: Vec::new(),
    };
    let fake = FakeAgones::start("127.0.0.1:0".parse().unwrap(), declared).unwrap();
    let mut options = load_server_options(4);
    options.game.time_limit_s = Some(8.0);
    options.stall_after = Duration::from_millis(500);
    let mut server = build_server(options).unwrap();
    let agones = AgonesOptions {
        port: Some(fake.addr.port()),
        health_every: Duration::from_millis(50),
        sync_every: Duration::from_millis(50),
    };
    let game = GameServerInfo { registry: server.registry.clone(), advertised: server.advertised };
    let services =
        FleetServices::start(&server.fleet, game, &FleetOptions { metrics: None, agones: Some(agones) }).unwrap();
    let long = Duration::from_secs(30);

    // Ready once the sockets are bound, the address and version told, capacities set from --max-sessions;
    // the watch stream is opened by its own task, so it is waited for too (it may come after the rest).
    assert!(run_until(&mut server, &mut [], &fake, long, |r| {
        r.ready == 1 && r.lists[PLAYERS_LIST].0 == 8 && r.calls.iter().any(|c| c == "WatchGameServer")
    }));
    let r = fake.recorded();
    assert_eq!(r.state, "Ready");
    assert_eq!(r.annotations.get("phantom-heist.address"), Some(&server.advertised.to_string()));
    assert!(r.labels.contains_key("phantom-heist.join-version"), "{:?}", r.labels);
    assert_eq!(r.counters[SESSIONS_COUNTER], (0, 4));
    assert!(r.calls.iter().any(|c| c == "WatchGameServer"), "{:?}", r.calls);
    // Health pings while the loop runs.
    assert!(run_until(&mut server, &mut [], &fake, long, |r| r.health_pings.len() >= 5));

    // A bot pair creates a session: the counter counts it, the list holds both seated players.
    let mut bots = create_bot_pair(&server, ViveStyle::Idle, 1, |_| {}).unwrap();
    assert!(run_until(&mut server, &mut bots, &fake, long, |r| {
        r.counters[SESSIONS_COUNTER].0 == 1 && r.lists[PLAYERS_LIST].1.len() == 2
    }));
    let players = fake.recorded().lists[PLAYERS_LIST].1.clone();
    assert!(players.iter().all(|p| p.len() == 32 && p.chars().all(|c| c.is_ascii_hexdigit())), "{players:?}");
    assert_ne!(players[0], players[1]);

    // The loop stalls (nobody updates it): the pings stop after the stall threshold, and resume with it.
    let stalled_at = Instant::now();
    std::thread::sleep(Duration::from_millis(1500));
    let resumed_at = Instant::now();
    let quiet_from = stalled_at + Duration::from_millis(500 + 50 + 100);
    let during: Vec<_> =
        fake.recorded().health_pings.into_iter().filter(|&t| t > quiet_from && t < resumed_at).collect();
    assert!(during.is_empty(), "{} health pings while the loop was stalled", during.len());
    let before = fake.recorded().health_pings.len();
    assert!(run_until(&mut server, &mut bots, &fake, long, |r| r.health_pings.len() >= before + 3), "pings resume");

    // An allocation reaches the server through its watch (it logs it; the state is the sidecar's).
    fake.allocate();
    assert!(run_until(&mut server, &mut bots, &fake, long, |r| r.state == "Allocated"));

    // A drain during the heist: the 8 s heist plays to its result, the session ends, the counter and
    // list empty, the capacity follows the count down (no allocation picks a draining server), the app
    // exits.
    let phase = server.sessions()[0].game.phase;
    assert_eq!(phase, heist_shared::protocol::Phase::Heist, "the heist is under way");
    assert!(server.fleet.drain.request());
    let deadline = Instant::now() + long;
    while server.should_exit().is_none() && Instant::now() < deadline {
        server.update();
        bots.iter_mut().for_each(App::update);
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(server.should_exit(), Some(AppExit::Success), "the drained server exits 0");
    assert!(server.sessions().is_empty());
    services.shut_down();
    let r = fake.recorded();
    assert_eq!(r.shutdown, 1, "Shutdown after the drain: {:?}", r.calls);
    assert_eq!(r.counters[SESSIONS_COUNTER], (0, 0));
    assert!(r.lists[PLAYERS_LIST].1.is_empty(), "{:?}", r.lists);
    let last = r.calls.iter().rposition(|c| c == "Shutdown").unwrap();
    assert_eq!(last, r.calls.len() - 1, "Shutdown is the last call: {:?}", r.calls);
}
