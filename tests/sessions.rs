//! A session over its life, over loopback UDP with secure tokens: rounds and rematches, who is told what
//! when a player comes, leaves or drops, and the end of a session nobody continues.

use heist_bots::ViveStyle;
use heist_server::ServerOptions;
use heist_server::build_server;
use heist_server::game::next_round_seed;
use heist_shared::protocol::{ClientMsg, DisconnectReason, GameEvent, LobbyMsg, LossReason, Phase, Role, ServerMsg};
use heist_tests::{HZ, Heist, Session};

/// Both plain clients joined and ready; the heist runs on a `time_limit_s` clock.
fn started(seed: u64, time_limit_s: f32, idle_end_s: Option<f32>) -> (Session, usize, usize) {
    let mut options = ServerOptions::local_test(seed);
    options.game.time_limit_s = Some(time_limit_s);
    options.game.idle_end_s = idle_end_s;
    let mut s = Session::with_options(options);
    let vive = s.join(Role::Vive, |_| {});
    let phantom = s.join(Role::Phantom, |_| {});
    assert!(s.step_until(5 * HZ, |s| s.server.game().present == (true, true)), "both are admitted");
    s.send(vive, ClientMsg::Lobby(LobbyMsg::Ready));
    s.send(phantom, ClientMsg::Lobby(LobbyMsg::Ready));
    assert!(s.step_until(5 * HZ, |s| s.server.game().phase == Phase::Heist), "the heist starts");
    (s, vive, phantom)
}

fn events_of(s: &Session, client: usize) -> &[GameEvent] {
    &s.inbox(client).events
}

#[test]
fn a_rematch_asked_by_both_plays_a_second_heist_on_a_new_seed_with_the_same_players() {
    // Careful bots on a short clock: they break cases and judge copies in both rounds.
    let mut options = ServerOptions::local_test(10);
    options.game.time_limit_s = Some(150.0);
    let mut heist = Heist::join_for_rounds(build_server(options).expect("server starts"), ViveStyle::Careful, 2)
        .expect("the bots join");
    let first = heist.run(160.0);
    assert!(matches!(first, Phase::Won | Phase::Lost(_)), "round 1 ended: {first:?}");
    let first_seed = heist.results[0].seed;
    assert_eq!(first_seed, 10);
    assert!(heist.await_next_round(10.0), "both bots asked and round 2 began");
    let game = heist.server.game();
    assert_eq!((game.round, game.seed), (2, next_round_seed(first_seed)));
    assert_eq!(game.present, (true, true));
    let second = heist.run(160.0);
    assert!(matches!(second, Phase::Won | Phase::Lost(_)), "round 2 ended: {second:?}");

    let log = heist.server.log().to_vec();
    let begins = log.iter().position(|l| l.contains("round 2 begins")).expect("round 2 is logged");
    let round_two = &log[begins..];
    let all = log.join("\n");
    assert!(round_two.iter().any(|l| l.contains("broken")), "Vive played round 2 too:\n{all}");
    assert!(round_two.iter().any(|l| l.contains("Phantom declares")), "Phantom judged in round 2:\n{all}");
    assert!(log.iter().filter(|l| l.contains("asks for another round")).count() == 2, "{all}");
    assert_eq!(log.iter().filter(|l| l.contains("phase: Won") || l.contains("phase: Lost")).count(), 2);
    // Phantom was briefed twice, each time on that round's copies; Vive heard the round begin.
    let phantom = heist.phantom.world().resource::<heist_client::Inbox>();
    assert_eq!((phantom.received.briefings, phantom.round), (2, 2));
    let vive = heist.vive.world().resource::<heist_client::Inbox>();
    assert!(vive.refusals.is_empty(), "Vive's moves of round 2 were all accepted: {:?}", vive.refusals);
}

#[test]
fn a_rematch_needs_both_and_a_partner_hears_the_request() {
    let (mut s, vive, phantom) = started(4, 1.0, None);
    assert!(s.step_until(3 * HZ, |s| !s.server.game().is_running()));
    assert_eq!(s.server.game().phase, Phase::Lost(LossReason::Time));
    s.send(vive, ClientMsg::Lobby(LobbyMsg::Rematch));
    s.step_until(HZ, |_| false);
    assert!(!s.server.game().is_running(), "one wish is not enough");
    assert!(events_of(&s, phantom).contains(&GameEvent::RematchAsked(Role::Vive)), "Phantom hears Vive ask");
    s.send(phantom, ClientMsg::Lobby(LobbyMsg::Rematch));
    assert!(s.step_until(2 * HZ, |s| s.server.game().phase == Phase::Heist), "round 2 begins");
    assert!(s.step_until(HZ, |s| s.inbox(vive).round == 2 && s.inbox(phantom).received.briefings == 2));
    assert!(events_of(&s, vive).contains(&GameEvent::RoundStarted(2)));
    assert_eq!(s.client_phase(vive), Some(Phase::Heist));
}

#[test]
fn a_player_who_leaves_is_heard_as_left_and_one_who_vanishes_as_dropped() {
    let (mut s, vive, phantom) = started(5, 600.0, None);
    assert!(events_of(&s, vive).contains(&GameEvent::Joined(Role::Phantom)), "Vive heard Phantom join");
    s.send(phantom, ClientMsg::Lobby(LobbyMsg::Leave));
    let left = GameEvent::Left { role: Role::Phantom, dropped: false };
    assert!(s.step_until(3 * HZ, |s| events_of(s, vive).contains(&left)), "Vive hears Phantom left");
    assert!(!s.server.game().is_present(Role::Phantom));

    // A new Phantom comes, then its process dies without a word: the server notices it dropped.
    let again = s.join(Role::Phantom, |_| {});
    assert!(s.step_until(5 * HZ, |s| s.server.game().is_present(Role::Phantom)), "the seat was free");
    drop(s.clients.remove(again));
    let dropped = GameEvent::Left { role: Role::Phantom, dropped: true };
    assert!(s.step_until(20 * HZ, |s| events_of(s, vive).contains(&dropped)), "Vive hears the drop");
    assert_eq!(s.server.game().phase, Phase::Heist, "within the grace period the heist goes on");
}

#[test]
fn a_session_nobody_continues_ends_and_both_players_are_told() {
    let (mut s, vive, phantom) = started(6, 1.0, Some(5.0));
    assert!(s.step_until(3 * HZ, |s| !s.server.game().is_running()));
    let told = |s: &Session, c: usize| s.inbox(c).disconnect == Some(DisconnectReason::SessionEnded);
    assert!(s.step_until(8 * HZ, |s| told(s, vive) && told(s, phantom)), "both were told the session ended");
    assert!(s.server.game().closed);
    assert!(s.server.log().iter().any(|l| l.contains("session ended: nobody asked for another round")));
}

#[test]
fn a_client_notices_within_seconds_that_the_server_went_silent_and_when_it_is_back() {
    use heist_client::{Link, SILENCE_LOST_S};
    use std::time::{Duration, Instant};
    let (mut s, vive, phantom) = started(7, 600.0, None);
    let link = |s: &Session, c: usize| *s.clients[c].world().resource::<Link>();
    assert_eq!((link(&s, vive), link(&s, phantom)), (Link::Up, Link::Up));
    // The server stalls (its process hangs, or the network drops everything): only the clients run.
    let stalled = Instant::now();
    let mut lost_after = None;
    while stalled.elapsed() < Duration::from_secs(8) {
        for c in &mut s.clients {
            c.update();
        }
        if link(&s, vive) == Link::Silent && link(&s, phantom) == Link::Silent {
            lost_after = Some(stalled.elapsed());
            break;
        }
        std::thread::sleep(Duration::from_millis(16));
    }
    let lost_after = lost_after.expect("both clients noticed the silence");
    // Not before the threshold (counted from the server's last packet, which may predate the stall by a
    // frame or two); before netcode's 6 s timeout (the margin is for a loaded machine).
    assert!(lost_after.as_secs_f64() >= SILENCE_LOST_S - 0.5, "{lost_after:?}");
    assert!(lost_after < Duration::from_secs(6), "{lost_after:?}");
    assert!(s.step_until(3 * HZ, |s| link(s, vive) == Link::Up && link(s, phantom) == Link::Up), "back");
}

/// Every server message a client got, in order (a reader of its own: the bots take theirs from the inbox).
#[derive(bevy::prelude::Resource, Default)]
struct Heard(Vec<ServerMsg>);

fn hear(mut messages: bevy::prelude::MessageReader<ServerMsg>, mut heard: bevy::prelude::ResMut<Heard>) {
    heard.0.extend(messages.read().cloned());
}

/// Replicated entities of each kind a client holds: (sessions, Vives, tools, guards, cases, items).
fn held(app: &mut bevy::prelude::App) -> [usize; 6] {
    use heist_shared::protocol::{CaseView, GuardView, ItemView, PhantomTool, SessionView, ViveAvatar};
    let world = app.world_mut();
    [
        world.query::<&SessionView>().iter(world).count(),
        world.query::<&ViveAvatar>().iter(world).count(),
        world.query::<&PhantomTool>().iter(world).count(),
        world.query::<&GuardView>().iter(world).count(),
        world.query::<&CaseView>().iter(world).count(),
        world.query::<&ItemView>().iter(world).count(),
    ]
}

/// The most of each kind one session has, as [`held`] counts them (its items, as many as it likes).
fn most_held() -> [usize; 6] {
    let level = heist_shared::level::Level::museum();
    [1, 1, 1, level.guards.len(), level.cases.len(), usize::MAX]
}

/// Looks at every client: none may hold another session's entities (more of a kind than one session has,
/// `most`); `seen[i]` becomes true once client `i` holds its own session whole — its session, Vive, tool,
/// every case, the guards its role gets (Vive's client, even, only those he perceives; Phantom's, odd, all
/// of them) and, `with_items`, at least one item.
fn check_clients(clients: &mut [bevy::prelude::App], most: [usize; 6], with_items: bool, seen: &mut [bool]) {
    for (i, client) in clients.iter_mut().enumerate() {
        let counts = held(client);
        assert!(counts.iter().zip(most).all(|(n, m)| *n <= m), "client {i} holds {counts:?}: another session's?");
        let guards_whole = i % 2 == 0 || counts[3] == most[3];
        seen[i] |= counts[..3] == [1, 1, 1] && guards_whole && counts[4] == most[4] && (!with_items || counts[5] > 0);
    }
}

/// A server with `n` sessions, each made by a careful Vive bot and a Phantom bot for one round of
/// `time_limit_s` that ends `idle_end_s` after its result; `probe` adds a test's systems to every client.
fn bot_sessions(
    n: usize,
    time_limit_s: f32,
    idle_end_s: f32,
    probe: impl Fn(&mut bevy::prelude::App) + Copy,
) -> (heist_server::HostedServer, Vec<bevy::prelude::App>) {
    let mut options = heist_server::load::load_server_options(n);
    options.game.time_limit_s = Some(time_limit_s);
    options.game.idle_end_s = Some(idle_end_s);
    let server = build_server(options).expect("server starts");
    let mut clients = Vec::with_capacity(2 * n);
    for _ in 0..n {
        clients.extend(heist_server::load::create_bot_pair(&server, ViveStyle::Careful, 1, probe).expect("a pair"));
    }
    assert_eq!(server.registry.len(), n);
    (server, clients)
}

/// Every one of the `n` sessions has played its round to a result.
fn all_over(server: &mut heist_server::HostedServer, n: usize) -> bool {
    let sessions = server.sessions();
    sessions.len() == n && sessions.iter().all(|s| !s.game.is_running() && s.game.phase != Phase::Lobby)
}

#[test]
fn twenty_sessions_of_bot_pairs_play_whole_heists_at_once_and_no_client_sees_another_sessions_entities_or_messages() {
    const SESSIONS: usize = 20;
    let probe = |app: &mut bevy::prelude::App| {
        app.init_resource::<Heard>().add_systems(bevy::prelude::PreUpdate, hear);
    };
    let (mut server, mut clients) = bot_sessions(SESSIONS, 60.0, 3.0, probe);
    assert!(server.shards.len() > 1, "the sessions are spread over shards, each a replication server of its own");
    let most = most_held();
    let mut all_running_at_once = false;
    let mut own_entities_seen = vec![false; clients.len()];
    let over = |server: &mut heist_server::HostedServer| all_over(server, SESSIONS);
    let mut ticks = 0;
    while !over(&mut server) && ticks < 90 * HZ {
        server.update();
        clients.iter_mut().for_each(bevy::prelude::App::update);
        ticks += 1;
        if ticks % 30 == 0 {
            let sessions = server.sessions();
            all_running_at_once |= sessions.len() == SESSIONS && sessions.iter().all(|s| s.game.is_running());
            check_clients(&mut clients, most, false, &mut own_entities_seen);
        }
    }
    assert!(over(&mut server), "every session played its heist to a result within {ticks} ticks");
    assert!(all_running_at_once, "the twenty heists ran at the same time");
    assert!(own_entities_seen.iter().all(|s| *s), "every client saw its own session whole");
    for _ in 0..10 {
        server.update();
        clients.iter_mut().for_each(bevy::prelude::App::update);
    }

    // Each client heard exactly its own session's story: one welcome, one heist start, its own result,
    // and only the cases its own session broke.
    let mut seeds = std::collections::HashSet::new();
    let mut games: Vec<(u64, Phase, Vec<u16>)> = Vec::new();
    for s in server.sessions() {
        let broken = s.game.cases.iter().enumerate().filter(|(_, c)| c.broken).map(|(i, _)| i as u16).collect();
        seeds.insert(s.game.seed);
        games.push((s.id, s.game.phase, broken));
    }
    assert_eq!(seeds.len(), SESSIONS, "every session drew its own seed");
    for (i, client) in clients.iter().enumerate() {
        let heard = &client.world().resource::<Heard>().0;
        let welcomes = heard.iter().filter(|m| matches!(m, ServerMsg::Welcome { .. })).count();
        let events: Vec<&GameEvent> =
            heard.iter().filter_map(|m| if let ServerMsg::Event(e) = m { Some(e) } else { None }).collect();
        let starts = events.iter().filter(|e| **e == &GameEvent::PhaseChanged(Phase::Heist)).count();
        let results: Vec<Phase> = events
            .iter()
            .filter_map(|e| match e {
                GameEvent::PhaseChanged(p @ (Phase::Won | Phase::Lost(_))) => Some(*p),
                _ => None,
            })
            .collect();
        let mut broken: Vec<u16> =
            events.iter().filter_map(|e| if let GameEvent::CaseBroken(c) = e { Some(c.0) } else { None }).collect();
        broken.sort_unstable();
        assert_eq!((welcomes, starts, results.len()), (1, 1, 1), "client {i} heard one session");
        let own = games.iter().filter(|(_, phase, cases)| *phase == results[0] && *cases == broken).count();
        assert!(own >= 1, "client {i} heard {results:?} and cases {broken:?}: no session played that");
        // Its partner (the other client of the pair) heard the same story.
        let partner = &clients[i ^ 1].world().resource::<Heard>().0;
        let partner_broken = partner.iter().filter(|m| matches!(m, ServerMsg::Event(GameEvent::CaseBroken(_)))).count();
        assert_eq!(partner_broken, broken.len(), "client {i} and its partner heard the same session");
    }

    // Over, the sessions end and free what they held: codes, seats, games, mirrors.
    let freed = |server: &mut heist_server::HostedServer| {
        server.sessions().is_empty() && server.registry.is_empty() && mirrors(server) == 0
    };
    let mut ticks = 0;
    while !freed(&mut server) && ticks < 30 * HZ {
        server.update();
        clients.iter_mut().for_each(bevy::prelude::App::update);
        ticks += 1;
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    assert!(freed(&mut server), "every session ended and freed its game, mirrors, code and seats");
    for client in &clients {
        let inbox = client.world().resource::<heist_client::Inbox>();
        assert_eq!(inbox.disconnect, Some(DisconnectReason::SessionEnded), "each player is told");
    }
}

/// Every replicated mirror on the server, over all its shards.
fn mirrors(server: &mut heist_server::HostedServer) -> usize {
    let mut n = 0;
    for shard in &mut server.shards {
        let world = shard.app.world_mut();
        n += world.query::<&bevy_replicon::prelude::Replicated>().iter(world).count();
    }
    n
}

#[test]
fn three_hundred_sessions_in_one_process_are_created_played_and_closed_and_no_client_sees_another_sessions_entities() {
    const SESSIONS: usize = 300;
    let (mut server, mut clients) = bot_sessions(SESSIONS, 8.0, 1.0, |_| {});
    assert_eq!(server.shards.len(), SESSIONS.div_ceil(server.registry.shard_size()), "spread over shards");
    let most = most_held();
    let mut own_seen = vec![false; clients.len()];
    let mut most_running = 0;
    let step = |server: &mut heist_server::HostedServer, clients: &mut Vec<bevy::prelude::App>| {
        server.update();
        clients.iter_mut().for_each(bevy::prelude::App::update);
    };
    let over = |server: &mut heist_server::HostedServer| all_over(server, SESSIONS);
    let mut ticks = 0;
    while !over(&mut server) && ticks < 30 * HZ {
        step(&mut server, &mut clients);
        ticks += 1;
        if ticks % 20 == 0 {
            most_running = most_running.max(server.sessions().iter().filter(|s| s.game.is_running()).count());
            check_clients(&mut clients, most, true, &mut own_seen);
        }
    }
    assert!(over(&mut server), "every session played its heist to a result within {ticks} ticks");
    assert_eq!(most_running, SESSIONS, "the heists ran at the same time");
    let unseen: Vec<usize> = (0..clients.len()).filter(|i| !own_seen[*i]).collect();
    assert!(unseen.is_empty(), "clients {unseen:?} never held their own session whole");
    // Each shard's netcode has slots for its own sessions' players (each twice, and 16 more), not for
    // the server's 600.
    for shard in &server.shards {
        let transport = shard.app.world().resource::<heist_server::net::transport::GameTransport>();
        assert_eq!(transport.max_clients(), 4 * 8 + 16, "a shard's netcode slots");
        // A shard is a server only: replicon's client side (its resources and its systems every tick)
        // is left out although the crate is built with it.
        let world = shard.app.world();
        assert!(!world.contains_resource::<bevy_replicon::client::ServerUpdateTick>(), "replicon's client side");
    }

    // Over, every session closes and frees what it held.
    let mut ticks = 0;
    while !(server.sessions().is_empty() && server.registry.is_empty() && mirrors(&mut server) == 0) && ticks < 20 * HZ
    {
        step(&mut server, &mut clients);
        ticks += 1;
    }
    assert!(server.registry.is_empty(), "{} sessions still open after {ticks} ticks", server.registry.len());
    assert_eq!(mirrors(&mut server), 0, "every mirror despawned");
    for _ in 0..5 {
        step(&mut server, &mut clients);
    }
    let told = clients
        .iter()
        .filter(|c| c.world().resource::<heist_client::Inbox>().disconnect == Some(DisconnectReason::SessionEnded))
        .count();
    assert_eq!(told, clients.len(), "every player is told the session ended");
}
