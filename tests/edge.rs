//! The network edge under attack on loopback: crafted and random datagrams, idle and slow connections,
//! code guessing, and what a passive observer of a join sees.

#![allow(clippy::unwrap_used)] // helpers outside the #[test] fns unwrap too: a panic fails the test

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use heist_client::{JoinError, request_token};
use heist_server::net::transport::GameTransport;
use heist_server::{ServerOptions, build_server};
use heist_shared::protocol::join::JoinRefusal;
use heist_shared::protocol::{Phase, Role};
use heist_tests::{HZ, Heist, UdpAttacker, token_for};
use heist_transport::memory::crafted::{crashing_prefix, huge_sequence, renet_slice, short_with_long_sequence};
use rand::{Rng, SeedableRng};

/// renet's channel 0 on the server: the first client channel (replicon's mutation acks, reliable).
const RELIABLE: u8 = 0;

#[test]
fn crafted_datagrams_from_every_kind_of_address_leave_a_real_heist_running() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
    let mut server = build_server(heist_tests::easy(19)).expect("server starts");
    // Tokens minted while both roles are free: every attacker holds a real one.
    let mut intruder = UdpAttacker::new(token_for(&server, Role::Vive));
    let mut pending = UdpAttacker::new(token_for(&server, Role::Phantom));
    let mut third = UdpAttacker::new(token_for(&server, Role::Phantom));
    let stranger = UdpSocket::bind("127.0.0.1:0").unwrap();
    let to = server.addr;

    // A malicious Vive connects and is admitted: its address is a connected one.
    for _ in 0..10 * HZ {
        intruder.pump();
        server.update();
        if server.game().is_present(Role::Vive) && intruder.netcode.is_connected() {
            break;
        }
    }
    assert!(server.game().is_present(Role::Vive) && intruder.netcode.is_connected(), "the intruder got in");
    intruder.send_raw(&crashing_prefix());
    intruder.send_raw(&short_with_long_sequence());
    intruder.send_raw(&huge_sequence());
    intruder.send_sealed(&renet_slice(RELIABLE, 0, 5, 2));
    intruder.send_sealed(&renet_slice(RELIABLE, 1, 0, 2));
    intruder.send_sealed(&renet_slice(RELIABLE, 1, 7, 8));
    server.update();

    // Another token holder sends its connection request and never answers the challenge: its address is
    // a pending one.
    pending.pump();
    server.update();
    pending.send_raw(&crashing_prefix());
    pending.send_raw(&short_with_long_sequence());
    server.update();

    // Random datagrams from all three kinds of address, and random payloads sealed with a session key.
    for i in 0..900 {
        let len = rng.random_range(0..1400);
        let junk: Vec<u8> = (0..len).map(|_| rng.random()).collect();
        match i % 3 {
            0 => stranger.send_to(&junk, to).map(drop).unwrap(),
            1 => pending.send_raw(&junk),
            _ => intruder.send_sealed(&junk[..len.min(1200)]),
        }
        if i % 30 == 0 {
            server.update();
        }
    }
    for _ in 0..5 {
        server.update();
    }
    let stats = server.world().resource::<GameTransport>().stats();
    assert!(stats.refused_datagrams >= 300, "{stats:?}");
    assert!(stats.refused_payloads >= 2, "both crafted slices were refused: {stats:?}");

    // The intruder leaves; real players take the seats and play a whole heist, while a refused third
    // client and a stranger keep sending crafted and random datagrams.
    intruder.leave();
    assert!(
        (0..5 * HZ).any(|_| {
            server.update();
            !server.game().is_present(Role::Vive)
        }),
        "the intruder's seat is free"
    );
    let mut heist = Heist::join(server, heist_bots::ViveStyle::Careful).expect("the bots join");
    for tick in 0..(800 * HZ) {
        heist.step();
        if tick % 20 == 0 {
            third.pump();
            third.send_sealed(&renet_slice(RELIABLE, (tick / 20 % 50) as u8, 9, 2));
            third.send_raw(&crashing_prefix());
            let junk: Vec<u8> = (0..rng.random_range(18..200)).map(|_| rng.random()).collect();
            stranger.send_to(&junk, to).unwrap();
        }
        if !heist.server.game().is_running() {
            break;
        }
    }
    assert_eq!(
        heist.server.game().phase,
        Phase::Won,
        "{:#?}",
        &heist.server.log()[heist.server.log().len().saturating_sub(15)..]
    );
}

#[test]
fn idle_and_slow_connections_never_delay_a_join() {
    let server = build_server(ServerOptions::local_test(1)).expect("server starts");
    let tokens = server.tokens.as_ref().unwrap();
    let (endpoint, code) = (tokens.addr, server.codes.as_ref().expect("a host session").current().code);
    let idle: Vec<TcpStream> = (0..200).map(|_| TcpStream::connect(endpoint).expect("connects")).collect();
    // One connection dribbles its hello a byte at a time.
    let slow = std::thread::spawn(move || {
        let mut s = TcpStream::connect(endpoint).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        let started = Instant::now();
        for _ in 0..4 {
            if s.write_all(&[0]).is_err() {
                break;
            }
            std::thread::sleep(Duration::from_millis(700));
        }
        let _ = s.read(&mut [0u8; 64]);
        started.elapsed()
    });
    std::thread::sleep(Duration::from_millis(200));
    for _ in 0..3 {
        let started = Instant::now();
        request_token(endpoint, &code, Role::Vive, Duration::from_secs(5)).expect("a token");
        let took = started.elapsed();
        assert!(took < Duration::from_millis(100), "a join took {took:?} beside 200 idle connections and a slow one");
    }
    let slow_lasted = slow.join().unwrap();
    assert!(slow_lasted < Duration::from_millis(3500), "the slow connection was cut at the deadline ({slow_lasted:?})");
    // Every idle connection was closed: pushed out by newer ones, or at its deadline.
    for mut s in idle {
        s.set_read_timeout(Some(Duration::from_secs(3))).unwrap();
        assert!(matches!(s.read(&mut [0u8; 8]), Ok(0) | Err(_)), "an idle connection is closed");
    }
}

fn wrong_code(code: &str) -> String {
    let last = code.chars().last().unwrap();
    format!("{}{}", &code[..code.len() - 1], if last == 'A' { 'B' } else { 'A' })
}

fn refusal(result: Result<impl std::fmt::Debug, JoinError>) -> JoinRefusal {
    match result {
        Err(JoinError::Refused(r)) => r,
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn wrong_codes_slow_down_then_the_sixth_from_an_address_is_refused() {
    let server = build_server(ServerOptions::local_test(1)).expect("server starts");
    let tokens = server.tokens.as_ref().unwrap();
    let (endpoint, code) = (tokens.addr, server.codes.as_ref().expect("a host session").current().code);
    let wrong = wrong_code(&code);
    let t = Duration::from_secs(5);
    let mut took = Vec::new();
    for _ in 0..5 {
        let started = Instant::now();
        assert_eq!(refusal(request_token(endpoint, &wrong, Role::Vive, t)), JoinRefusal::WrongCode);
        took.push(started.elapsed());
    }
    assert!(took[..3].iter().all(|d| *d < Duration::from_millis(400)), "the first three at once: {took:?}");
    assert!(took[3] >= Duration::from_millis(450) && took[4] >= Duration::from_millis(950), "then slower: {took:?}");
    assert!(matches!(refusal(request_token(endpoint, &wrong, Role::Vive, t)), JoinRefusal::TooManyWrongCodes { .. }));
    assert!(
        matches!(refusal(request_token(endpoint, &code, Role::Vive, t)), JoinRefusal::TooManyWrongCodes { retry_after_s } if retry_after_s > 50),
        "the address is refused even with the right code: no guess is checked"
    );
}

#[test]
fn codes_expire_and_the_host_can_rotate_them() {
    let mut options = ServerOptions::local_test(1);
    options.code_ttl = Duration::from_millis(300);
    let server = build_server(options).expect("server starts");
    let tokens = server.tokens.as_ref().unwrap();
    let old = server.codes.as_ref().expect("a host session").current().code;
    std::thread::sleep(Duration::from_millis(400));
    let t = Duration::from_secs(5);
    assert_eq!(refusal(request_token(tokens.addr, &old, Role::Vive, t)), JoinRefusal::CodeExpired);
    let fresh = server.codes.as_ref().expect("a host session").rotate().code;
    assert!(request_token(tokens.addr, &fresh, Role::Vive, t).is_ok(), "the new code works");
    assert_eq!(refusal(request_token(tokens.addr, &old, Role::Phantom, t)), JoinRefusal::WrongCode);
}

/// A TCP relay that records every byte in both directions.
fn recording_relay(to: SocketAddr) -> (SocketAddr, Arc<Mutex<Vec<u8>>>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    let seen = Arc::new(Mutex::new(Vec::new()));
    let record = seen.clone();
    std::thread::spawn(move || {
        let Ok((client, _)) = listener.accept() else { return };
        let server = TcpStream::connect(to).unwrap();
        let pipe = |mut from: TcpStream, mut into: TcpStream, seen: Arc<Mutex<Vec<u8>>>| {
            std::thread::spawn(move || {
                let mut buf = [0u8; 4096];
                while let Ok(n @ 1..) = from.read(&mut buf) {
                    seen.lock().unwrap().extend_from_slice(&buf[..n]);
                    if into.write_all(&buf[..n]).is_err() {
                        break;
                    }
                }
                let _ = into.shutdown(std::net::Shutdown::Write);
            })
        };
        let a = pipe(client.try_clone().unwrap(), server.try_clone().unwrap(), record.clone());
        let b = pipe(server, client, record);
        let _ = (a.join(), b.join());
    });
    (addr, seen)
}

fn contains(haystack: &[u8], needle: &[u8]) -> bool {
    haystack.windows(needle.len()).any(|w| w == needle)
}

/// Every form in which a secret could be spelled out on the wire: raw, hex, and for text, any case.
fn leaks(wire: &[u8], secret: &[u8]) -> bool {
    let hex: String = secret.iter().map(|b| format!("{b:02x}")).collect();
    let lower = wire.to_ascii_lowercase();
    contains(wire, secret) || contains(&lower, hex.as_bytes()) || contains(&lower, &secret.to_ascii_lowercase())
}

#[test]
fn a_passive_observer_of_a_join_learns_neither_the_code_nor_the_token_nor_its_keys() {
    let server = build_server(ServerOptions::local_test(1)).expect("server starts");
    let tokens = server.tokens.as_ref().unwrap();
    let code = server.codes.as_ref().expect("a host session").current().code;
    let (relay, wire) = recording_relay(tokens.addr);
    let token = request_token(relay, &code, Role::Phantom, Duration::from_secs(5)).expect("a token through the relay");
    std::thread::sleep(Duration::from_millis(100));
    let wire = wire.lock().unwrap().clone();
    assert!(wire.len() > 1200, "the whole exchange was captured ({} bytes)", wire.len());
    let mut token_bytes = Vec::new();
    token.write(&mut token_bytes).unwrap();
    // The check itself would see a token sent in clear.
    assert!(leaks(&[b"{...}".as_slice(), &token_bytes].concat(), &token.client_to_server_key));
    let secrets: [(&str, &[u8]); 6] = [
        ("the code", code.as_bytes()),
        ("the code without its dash", code.replace('-', "").as_bytes().to_vec().leak()),
        ("the client-to-server key", &token.client_to_server_key),
        ("the server-to-client key", &token.server_to_client_key),
        ("the token's private part", &token.private_data[..32]),
        ("the token's nonce", &token.xnonce),
    ];
    for (what, secret) in secrets {
        assert!(!leaks(&wire, secret), "{what} crossed the wire in clear");
    }
    for chunk in token_bytes.chunks(32) {
        assert!(chunk.len() < 16 || !contains(&wire, chunk), "a piece of the token crossed the wire in clear");
    }
}
