//! Seats over loopback UDP with secure tokens: a player whose client dies takes the seat back with the
//! ticket kept in its seat cache, gets what its view needs, and plays on; nobody else can take a kept
//! seat; a kept seat that is not taken back is given up and the heist lost.

use bevy::prelude::*;
use heist_bots::{PhantomBotPlugin, ViveBotPlugin, ViveStyle};
use heist_client::{JoinError, SeatCache};
use heist_server::{HostedServer, ServerOptions, build_server};
use heist_shared::protocol::join::JoinRefusal;
use heist_shared::protocol::{ClientMsg, GameEvent, LobbyMsg, LossReason, Phase, Role};
use heist_shared::rules::SEAT_HOLD_S;
use heist_tests::{HZ, Heist, Session, easy, join_with_seat, seat_cache, token_for};

fn vive_bot(app: &mut App) {
    app.add_plugins(ViveBotPlugin { style: ViveStyle::Careful });
}

fn phantom_bot(app: &mut App) {
    app.add_plugins(PhantomBotPlugin::default());
}

/// Both bots joined through their seat caches.
fn bots(seed: u64, vive: &SeatCache, phantom: &SeatCache) -> Heist {
    let server = build_server(easy(seed)).expect("server starts");
    let (v, resumed_v) = join_with_seat(&server, Role::Vive, vive, vive_bot).expect("Vive joins");
    let (p, resumed_p) = join_with_seat(&server, Role::Phantom, phantom, phantom_bot).expect("Phantom joins");
    assert!(!resumed_v && !resumed_p, "a first join takes a free seat");
    Heist { server, vive: v, phantom: p, ticks: 0, results: Vec::new() }
}

/// Steps the server and the one client left (`app`) for `ticks`.
fn step_alone(server: &mut HostedServer, app: &mut App, ticks: u64) {
    for _ in 0..ticks {
        server.update();
        app.update();
    }
}

fn step_heist_until(heist: &mut Heist, max_ticks: u64, done: impl Fn(&Heist) -> bool) -> bool {
    for _ in 0..max_ticks {
        heist.step();
        if done(heist) {
            return true;
        }
    }
    false
}

fn refusal(result: Result<impl Sized, JoinError>) -> JoinRefusal {
    match result {
        Err(JoinError::Refused(r)) => r,
        Err(e) => panic!("expected a refusal, got {e}"),
        Ok(_) => panic!("expected a refusal, got a token"),
    }
}

#[test]
fn a_vive_killed_mid_heist_takes_his_seat_back_within_seconds_moves_again_and_the_heist_is_won() {
    let (vive_cache, phantom_cache) = (seat_cache("vive"), seat_cache("phantom"));
    // Seed 1 on easy, Vive killed 45 s in: the careful bots win it after the restart (deterministic:
    // stepped clock). A restarted bot starts with a fresh brain, so like any heist not every seed and
    // moment is won.
    let mut heist = bots(1, &vive_cache, &phantom_cache);
    assert!(step_heist_until(&mut heist, 90 * HZ, |h| h.server.game().elapsed_s >= 45.0), "45 s of heist");
    let endpoint = heist.server.tokens.as_ref().expect("endpoint").addr;
    assert!(vive_cache.load(endpoint, Role::Vive).is_some(), "Vive's client kept its seat ticket");

    // Vive's process dies without a word; 5 s later he starts his client again.
    let killed = std::mem::replace(&mut heist.vive, App::new());
    drop(killed);
    step_alone(&mut heist.server, &mut heist.phantom, 5 * HZ);
    let (vive, resumed) = join_with_seat(&heist.server, Role::Vive, &vive_cache, vive_bot).expect("Vive comes back");
    assert!(resumed, "the cached ticket took the seat back");
    heist.vive = vive;
    // (The Phantom bot takes the events it hears; the server's log shows what it sent.)
    assert!(
        step_heist_until(&mut heist, 5 * HZ, |h| h.server.log().iter().any(|l| l.contains("Vive is back"))),
        "Vive's seat is taken back and Phantom told"
    );
    let at = heist.server.game().vive.position;
    assert!(
        step_heist_until(&mut heist, 40 * HZ, |h| h.server.game().vive.position.distance(at) > 0.5),
        "Vive's new connection moves him (his move numbers started afresh): at {at:?}, now {:?}, seq {}, paused {}\n{}",
        heist.server.game().vive.position,
        heist.server.game().vive.last_input_seq,
        heist.server.game().is_paused(),
        heist.server.log().join("\n")
    );
    let phase = heist.run(750.0);
    assert_eq!(phase, Phase::Won, "after the resume the heist is still won:\n{}", heist.server.log().join("\n"));
    assert!(heist.server.log().iter().any(|l| l.contains("Vive is back")));
    let vive_inbox = heist.vive.world().resource::<heist_client::Inbox>();
    assert!(vive_inbox.resumed, "the welcome said the seat was taken back");
}

#[test]
fn a_phantom_back_gets_the_briefings_and_the_copy_on_the_bench_and_judges_it() {
    let (vive_cache, phantom_cache) = (seat_cache("vive"), seat_cache("phantom"));
    let mut heist = bots(10, &vive_cache, &phantom_cache);
    assert!(
        step_heist_until(&mut heist, 400 * HZ, |h| h.server.game().workbench.is_some()),
        "a copy reaches the bench"
    );
    let on_bench = heist.server.game().workbench.expect("a copy");

    // Phantom's process dies while the copy lies there.
    drop(std::mem::replace(&mut heist.phantom, App::new()));
    let dropped = GameEvent::Left { role: Role::Phantom, dropped: true };
    // Netcode notices a silent client after 6 s of real time (however fast the stepped clock runs).
    let since = std::time::Instant::now();
    let mut noticed = false;
    while !noticed && since.elapsed() < std::time::Duration::from_secs(30) {
        step_alone(&mut heist.server, &mut heist.vive, 1);
        noticed = heist.vive.world().resource::<heist_client::Inbox>().events.contains(&dropped);
    }
    assert!(noticed, "the server noticed the drop and told Vive");

    // The seat is kept: a stranger with the join code is refused, and the heist stands still.
    let tokens = heist.server.tokens.as_ref().expect("endpoint");
    let code = heist.server.codes.as_ref().expect("a host session").current().code;
    let stranger =
        refusal(heist_client::request_token(tokens.addr, &code, Role::Phantom, std::time::Duration::from_secs(5)));
    assert!(matches!(stranger, JoinRefusal::SeatHeld { role: Role::Phantom, for_s: 1..=60 }), "{stranger:?}");
    let (left, elapsed) = (heist.server.game().time_left_s, heist.server.game().elapsed_s);
    step_alone(&mut heist.server, &mut heist.vive, 10 * HZ);
    let g = heist.server.game();
    assert_eq!((g.time_left_s, g.elapsed_s, g.phase), (left, elapsed, Phase::Heist), "the timer stood still");

    let (phantom, resumed) =
        join_with_seat(&heist.server, Role::Phantom, &phantom_cache, phantom_bot).expect("Phantom comes back");
    assert!(resumed);
    heist.phantom = phantom;
    let caught_up = |h: &Heist| {
        let inbox = h.phantom.world().resource::<heist_client::Inbox>();
        !inbox.briefings.is_empty() && inbox.received.workbench > 0
    };
    assert!(step_heist_until(&mut heist, 5 * HZ, caught_up), "Phantom got the briefings and the copy again");
    let judged = format!("Phantom declares copy #{}", on_bench.0);
    assert!(
        step_heist_until(&mut heist, 120 * HZ, |h| h.server.log().iter().any(|l| l.contains(&judged))),
        "Phantom judged the copy on the bench:\n{}",
        heist.server.log().join("\n")
    );
    assert!(heist.server.game().time_left_s < left, "the clock runs again");
}

#[test]
fn a_kept_seat_nobody_takes_back_is_given_up_and_the_heist_lost_as_abandoned() {
    let mut options = ServerOptions::local_test(31);
    options.game.time_limit_s = Some(600.0);
    let mut s = Session::with_options(options);
    let vive = s.join(Role::Vive, |_| {});
    let phantom = s.join(Role::Phantom, |_| {});
    assert!(s.step_until(5 * HZ, |s| s.server.game().present == (true, true)));
    s.send(vive, ClientMsg::Lobby(LobbyMsg::Ready));
    s.send(phantom, ClientMsg::Lobby(LobbyMsg::Ready));
    assert!(s.step_until(5 * HZ, |s| s.server.game().phase == Phase::Heist));
    drop(s.clients.remove(phantom));
    let since = std::time::Instant::now();
    while !s.server.game().is_seat_kept(Role::Phantom) && since.elapsed() < std::time::Duration::from_secs(30) {
        s.step();
    }
    assert!(s.server.game().is_seat_kept(Role::Phantom), "the drop is noticed (netcode's 6 s timeout)");
    let ticks = (f64::from(SEAT_HOLD_S) * HZ as f64) as u64;
    assert!(!s.step_until(ticks - HZ, |s| s.server.game().phase != Phase::Heist), "kept for the whole minute");
    assert!(s.step_until(2 * HZ, |s| s.server.game().phase == Phase::Lost(LossReason::Abandoned)));
    assert!(s.step_until(HZ, |s| s.inbox(vive).events.contains(&GameEvent::GaveUp(Role::Phantom))), "Vive is told");
    s.step();
    // The seat is free again: the code gives it to anyone.
    let _ = token_for(&s.server, Role::Phantom);
}

#[test]
fn a_ticket_only_takes_its_own_seat_back() {
    let (vive_cache, phantom_cache) = (seat_cache("vive"), seat_cache("phantom"));
    let mut heist = bots(32, &vive_cache, &phantom_cache);
    assert!(step_heist_until(&mut heist, 5 * HZ, |h| h.server.game().phase == Phase::Heist));
    let endpoint = heist.server.tokens.as_ref().expect("endpoint").addr;
    let vive_ticket = vive_cache.load(endpoint, Role::Vive).expect("Vive's ticket");
    let t = std::time::Duration::from_secs(5);
    // Vive's ticket does not open Phantom's seat, and a made-up one opens nothing.
    let wrong_seat = heist_client::request_resume_token(endpoint, Role::Phantom, &vive_ticket, t);
    assert_eq!(refusal(wrong_seat), JoinRefusal::NoSeat(Role::Phantom));
    let made_up =
        heist_client::request_resume_token(endpoint, Role::Vive, &heist_shared::protocol::SeatTicket::random(), t);
    assert_eq!(refusal(made_up), JoinRefusal::NoSeat(Role::Vive));
    // Someone who saw a resume go by knows the seat's public id, not its ticket: refused.
    let forged = forged_resume(endpoint, Role::Vive, vive_ticket.public_id());
    assert_eq!(forged, JoinRefusal::WrongTicket);
    // A stale ticket in a cache, for a seat nobody holds, falls back to the code.
    let stale = seat_cache("stale");
    let server = build_server(ServerOptions::local_test(33)).expect("a second server");
    let endpoint2 = server.tokens.as_ref().expect("endpoint").addr;
    stale.store(endpoint2, Role::Vive, &vive_ticket).expect("stored");
    let (_, resumed) = join_with_seat(&server, Role::Vive, &stale, |_| {}).expect("joins with the code");
    assert!(!resumed, "no seat was kept there: joined anew");
    let _ = std::fs::remove_dir_all(stale.dir());
}

/// A resume naming `seat` (as an observer of another resume saw it) keyed by a ticket of its own: the
/// server's answer to the confirmation.
fn forged_resume(endpoint: std::net::SocketAddr, role: Role, seat: [u8; 16]) -> JoinRefusal {
    use heist_shared::protocol::join::{self, JOIN_VERSION, JoinMsg, JoinReply, MAX_FRAME, Pake};
    use std::io::{Read, Write};
    let read = |stream: &mut std::net::TcpStream| {
        let mut header = [0u8; 2];
        stream.read_exact(&mut header).expect("a frame header");
        let mut body = vec![0u8; join::frame_len(header, MAX_FRAME).expect("a frame length")];
        stream.read_exact(&mut body).expect("a frame");
        body
    };
    let mut stream = std::net::TcpStream::connect(endpoint).expect("the endpoint");
    stream.set_read_timeout(Some(std::time::Duration::from_secs(5))).expect("a timeout");
    let (pake, ours) = Pake::client_ticket(&heist_shared::protocol::SeatTicket::random());
    let hello = join::frame(&JoinMsg::Resume { version: JOIN_VERSION, role, seat, pake: ours });
    stream.write_all(&hello).expect("sent");
    let challenge = read(&mut stream);
    let Ok(JoinReply::Challenge { pake: theirs }) = join::decode(&challenge) else { panic!("no challenge") };
    let keys = pake.finish(&theirs, &hello[2..], &challenge).expect("keys");
    stream.write_all(&join::frame(&JoinMsg::Confirm { mac: *keys.client_mac.as_bytes() })).expect("sent");
    match join::decode(&read(&mut stream)) {
        Ok(JoinReply::Refused(r)) => r,
        other => panic!("not refused: {other:?}"),
    }
}

fn reconnect(app: &App) -> heist_client::Reconnect {
    app.world().resource::<heist_client::Reconnect>().clone()
}

#[test]
fn clients_that_lose_the_server_take_their_seats_back_by_themselves() {
    use std::time::{Duration, Instant};
    let (vive_cache, phantom_cache) = (seat_cache("vive"), seat_cache("phantom"));
    let mut heist = bots(10, &vive_cache, &phantom_cache);
    assert!(step_heist_until(&mut heist, 60 * HZ, |h| h.server.game().elapsed_s >= 10.0));
    // The game loop stalls for 5 s (the token endpoint, on its own thread, still answers): both clients
    // notice within 3 s and ask for their seats back.
    let stalled = Instant::now();
    while stalled.elapsed() < Duration::from_secs(5) {
        heist.vive.update();
        heist.phantom.update();
        std::thread::sleep(Duration::from_millis(16));
    }
    for (name, app) in [("Vive", &heist.vive), ("Phantom", &heist.phantom)] {
        assert!(
            matches!(reconnect(app), heist_client::Reconnect::Trying { attempts: 1.. }),
            "{name} tries to come back: {:?}",
            reconnect(app)
        );
    }
    let back = |h: &Heist| {
        [&h.vive, &h.phantom].iter().all(|a| {
            reconnect(a) == heist_client::Reconnect::Steady && a.world().resource::<heist_client::Inbox>().resumed
        })
    };
    assert!(step_heist_until(&mut heist, 10 * HZ, back), "both took their seats back on new connections");
    let log = heist.server.log();
    assert!(log.iter().any(|l| l.contains("Vive is back")) && log.iter().any(|l| l.contains("Phantom is back")));
    let phantom_inbox = heist.phantom.world().resource::<heist_client::Inbox>();
    assert_eq!(phantom_inbox.received.briefings, 2, "Phantom got the briefings again on the new connection");
    let at = heist.server.game().vive.position;
    assert!(
        step_heist_until(&mut heist, 20 * HZ, |h| h.server.game().vive.position.distance(at) > 0.5),
        "Vive moves on the new connection"
    );
    assert!(heist.server.game().is_running(), "the heist goes on");
}

#[test]
fn a_client_whose_server_is_gone_retries_with_back_off_then_gives_up_saying_why() {
    use std::time::{Duration, Instant};
    let mut s = Session::new(34);
    let vive = s.join(Role::Vive, |_| {});
    assert!(s.step_until(5 * HZ, |s| s.inbox(vive).seat.is_some()), "welcomed with a seat ticket");
    let endpoint = s.server.tokens.as_ref().expect("endpoint").addr;
    s.clients[vive].insert_resource(heist_client::Rejoin::new(endpoint, Role::Vive).giving_up_after(4.0));
    // The server process ends: no game, no endpoint.
    let Session { server, mut clients } = s;
    drop(server);
    let app = &mut clients[vive];
    let since = Instant::now();
    let (mut tried_at, mut attempts) = (None, 0);
    while since.elapsed() < Duration::from_secs(15) && !matches!(reconnect(app), heist_client::Reconnect::GaveUp(_)) {
        app.update();
        if let heist_client::Reconnect::Trying { attempts: n } = reconnect(app) {
            tried_at.get_or_insert(since.elapsed());
            attempts = n;
        }
        std::thread::sleep(Duration::from_millis(16));
    }
    let tried_at = tried_at.expect("it tried");
    // Refused at once each time, it waits 0.5 s, 1 s, 2 s, 4 s… between attempts: 3 in a 4 s window.
    assert!((2..=4).contains(&attempts), "{attempts} attempts in 4 s (back-off)");
    assert!(tried_at < Duration::from_secs(5), "the loss was noticed within 3 s (and a frame): {tried_at:?}");
    let heist_client::Reconnect::GaveUp(why) = reconnect(app) else { panic!("it gave up: {:?}", reconnect(app)) };
    assert!(why.contains("no way back into the session for 4 s"), "{why}");
    let line =
        heist_client::notice::reconnect_notice(&heist_client::Reconnect::Trying { attempts: 1 }, &reconnect(app));
    assert!(line.is_some_and(|l| l.starts_with("Could not get back into the session")));
    let inbox = app.world().resource::<heist_client::Inbox>();
    assert!(heist_client::connection_over(*app.world().resource::<heist_client::Link>(), inbox, &reconnect(app)));
}

#[test]
fn a_client_that_quits_with_a_goodbye_frees_its_seat_instead_of_keeping_it() {
    let mut s = Session::new(35);
    let phantom = s.join(Role::Phantom, |_| {});
    let mut vive = heist_tests::UdpAttacker::new(token_for(&s.server, Role::Vive));
    let joined = (0..5 * HZ).any(|_| {
        vive.pump();
        s.step();
        s.server.game().is_present(Role::Vive)
    });
    assert!(joined, "a bare netcode client takes the Vive seat");
    vive.leave();
    assert!(s.step_until(5 * HZ, |s| !s.server.game().is_present(Role::Vive)));
    assert!(!s.server.game().is_seat_kept(Role::Vive), "netcode's disconnect packet is a goodbye");
    let left = GameEvent::Left { role: Role::Vive, dropped: false };
    assert!(s.step_until(HZ, |s| s.inbox(phantom).events.contains(&left)), "Phantom hears Vive left");
    let _ = token_for(&s.server, Role::Vive);
}
