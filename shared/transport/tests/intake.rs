//! The intake against the packets that panic renetcode 2.0.0 and renet 2.0.1, and against thousands of
//! random and mutated datagrams from unknown, pending and connected addresses.

#![allow(clippy::unwrap_used)] // helpers outside the #[test] fns unwrap too: a panic fails the test

use std::net::SocketAddr;
use std::panic::{AssertUnwindSafe, catch_unwind};

use heist_transport::memory::crafted::{crashing_prefix, huge_sequence, short_with_long_sequence};
use heist_transport::memory::{MemoryClient, MemoryServer, RawClient, SERVER_ADDR, START, run};
use heist_transport::renet::{DefaultChannel, RenetServer};
use heist_transport::renetcode::{
    ClientAuthentication, NetcodeClient, NetcodeServer, ServerAuthentication, ServerConfig,
};
use heist_transport::{DatagramRefusal, PayloadRefusal, Refused};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

fn addr(last: u8, port: u16) -> SocketAddr {
    SocketAddr::from(([192, 168, 0, last], port))
}

/// A reliable renet slice on channel 2 (renet's default ordered channel) with a full 1200-byte payload (renet checks the size of a slice
/// that is not the last before it indexes, so only a full one reaches the bad index).
fn slice_packet(message_id: u64, index: u64, count: u64) -> Vec<u8> {
    varint_slice(true, 2, message_id, index, count, 1200)
}

/// Runs `f`, catching a panic (its message still goes to the test's output).
fn quiet<R>(f: impl FnOnce() -> R) -> std::thread::Result<R> {
    catch_unwind(AssertUnwindSafe(f))
}

/// True when `client` and the server can still exchange reliable messages both ways, and a message
/// large enough to be sliced reaches the client.
fn plays(server: &mut MemoryServer, client: &mut MemoryClient, id: u64) -> bool {
    let big = vec![7u8; 5000];
    server.renet.send_message(id, DefaultChannel::ReliableOrdered, big.clone());
    client.renet.send_message(DefaultChannel::ReliableOrdered, vec![1, 2, 3]);
    run(server, &mut [client], 20);
    let got_small = std::iter::from_fn(|| server.renet.receive_message(id, DefaultChannel::ReliableOrdered))
        .any(|m| m[..] == [1, 2, 3]);
    let got_big =
        std::iter::from_fn(|| client.renet.receive_message(DefaultChannel::ReliableOrdered)).any(|m| m[..] == big[..]);
    got_small && got_big && client.renet.is_connected()
}

#[test]
fn renetcode_panics_on_the_crashing_prefix_from_a_pending_address() {
    // The upstream bug, reproduced on the bare library (what the intake stands in front of).
    let memory = MemoryServer::new();
    let mut bare = bare_server();
    let attacker = addr(66, 4000);
    // The connection request a real token holder sends makes the address pending.
    let auth = ClientAuthentication::Secure { connect_token: memory.token(77) };
    let mut raw = NetcodeClient::new(START, auth).unwrap();
    let (request, _) = raw.update(std::time::Duration::ZERO).expect("a request is due");
    let mut request = request.to_vec();
    let _ = bare.process_packet(attacker, &mut request);
    let mut crash = crashing_prefix();
    let panicked = quiet(|| {
        let _ = bare.process_packet(attacker, &mut crash);
    });
    assert!(panicked.is_err(), "renetcode 2.0.0 panics");
}

/// A bare netcode server (no intake) with the in-memory network's key and address.
fn bare_server() -> NetcodeServer {
    NetcodeServer::new(ServerConfig {
        current_time: START,
        max_clients: 4,
        protocol_id: heist_transport::memory::PROTOCOL_ID,
        public_addresses: vec![SERVER_ADDR],
        authentication: ServerAuthentication::Secure { private_key: [0x42; 32] },
    })
}

/// A bare netcode server (no intake) with client 78 connected from the returned address.
fn bare_connected() -> (NetcodeServer, SocketAddr) {
    let memory = MemoryServer::new();
    let mut bare = bare_server();
    let player = addr(67, 4000);
    let mut client =
        NetcodeClient::new(START, ClientAuthentication::Secure { connect_token: memory.token(78) }).unwrap();
    // The handshake by hand: request, challenge, response, keep-alive.
    for _ in 0..4 {
        if let Some((packet, _)) = client.update(heist_transport::memory::FRAME) {
            let mut packet = packet.to_vec();
            let mut answer = match bare.process_packet(player, &mut packet) {
                heist_transport::renetcode::ServerResult::PacketToSend { payload, .. }
                | heist_transport::renetcode::ServerResult::ClientConnected { payload, .. } => payload.to_vec(),
                _ => Vec::new(),
            };
            if !answer.is_empty() {
                let _ = client.process_packet(&mut answer);
            }
        }
    }
    assert!(bare.is_client_connected(78), "connected by hand");
    (bare, player)
}

#[test]
fn renetcode_panics_on_a_short_datagram_with_a_long_sequence_from_a_connected_address() {
    let (mut bare, player) = bare_connected();
    let mut short = short_with_long_sequence();
    let panicked = quiet(|| {
        let _ = bare.process_packet(player, &mut short);
    });
    assert!(panicked.is_err(), "renetcode 2.0.0 subtracts the tag length from a 9-byte rest and panics");
}

#[test]
fn renetcode_overflows_its_replay_window_on_a_huge_sequence_where_overflow_is_checked() {
    // Found by the fuzz target. Debug builds (and the fuzzer) check overflow; release builds wrap.
    let (mut bare, player) = bare_connected();
    let mut huge = huge_sequence();
    let panicked = quiet(|| {
        let _ = bare.process_packet(player, &mut huge);
    });
    assert_eq!(panicked.is_err(), cfg!(debug_assertions), "replay_protection.rs:25 adds 256 to u64::MAX");
}

#[test]
fn renet_panics_on_an_out_of_range_slice() {
    let mut bare = RenetServer::new(Default::default());
    bare.add_connection(1);
    assert!(quiet(|| bare.process_packet_from(&slice_packet(0, 5, 2), 1)).is_err(), "renet 2.0.1 panics");
    let mut bare = RenetServer::new(Default::default());
    bare.add_connection(1);
    let _ = bare.process_packet_from(&slice_packet(0, 0, 2), 1);
    assert!(quiet(|| bare.process_packet_from(&slice_packet(0, 7, 8), 1)).is_err(), "a changed count panics too");
}

#[test]
fn the_intake_refuses_every_known_crash_and_keeps_serving() {
    let mut server = MemoryServer::new();
    let mut player = server.client(addr(1, 1000), 1);
    run(&mut server, &mut [&mut player], 10);
    assert!(player.renet.is_connected());
    let mut pending = RawClient::pending(&mut server, addr(2, 2000), 2);
    let mut connected = RawClient::connected(&mut server, addr(3, 3000), 3);
    assert!(connected.netcode.is_connected());

    for from in [pending.addr, connected.addr, addr(9, 9000)] {
        assert_eq!(
            server.deliver(from, &crashing_prefix()),
            Err(Refused::Datagram(DatagramRefusal::BadSequenceLength(15)))
        );
        assert_eq!(
            server.deliver(from, &short_with_long_sequence()),
            Err(Refused::Datagram(DatagramRefusal::TooShort(18)))
        );
    }
    let out_of_range = connected.seal(&slice_packet(0, 5, 2));
    assert_eq!(
        server.deliver(connected.addr, &out_of_range),
        Err(Refused::Payload(PayloadRefusal::SliceOutOfRange { index: 5, count: 2 }))
    );
    assert_eq!(server.deliver(connected.addr, &connected.seal(&slice_packet(1, 0, 2))), Ok(()));
    assert_eq!(
        server.deliver(connected.addr, &connected.seal(&slice_packet(1, 7, 8))),
        Err(Refused::Payload(PayloadRefusal::SliceCountChanged { message_id: 1, was: 2, now: 8 }))
    );
    // A well-formed connection request with a forged token passes the checks; netcode turns it away and
    // the intake says so.
    let mut forged = vec![0u8; heist_transport::datagram::CONNECTION_REQUEST_BYTES];
    forged[1..14].copy_from_slice(heist_transport::datagram::VERSION_INFO);
    forged[14..22].copy_from_slice(&heist_transport::memory::PROTOCOL_ID.to_le_bytes());
    forged[22..30].copy_from_slice(&u64::MAX.to_le_bytes());
    assert_eq!(
        server.deliver(addr(9, 9001), &forged),
        Err(Refused::Netcode(heist_transport::datagram::PacketKind::ConnectionRequest))
    );
    assert_eq!(server.intake.stats().refused_by_netcode, 1);
    // A pending client's payload is ignored by netcode; it never reaches renet either way.
    let from_pending = pending.seal(&slice_packet(0, 5, 2));
    let _ = server.deliver(pending.addr, &from_pending);
    assert!(plays(&mut server, &mut player, 1), "the player still plays");
}

#[test]
fn a_client_refuses_crafted_datagrams_even_from_the_servers_address() {
    // A spoofer on the LAN can send from the server's address; the bare netcode client would panic.
    let server = MemoryServer::new();
    let auth = ClientAuthentication::Secure { connect_token: server.token(5) };
    let mut bare = NetcodeClient::new(START, auth).unwrap();
    let mut crash = crashing_prefix();
    assert!(quiet(|| bare.process_packet(&mut crash).is_some()).is_err(), "renetcode 2.0.0 panics in the client too");

    let mut server = MemoryServer::new();
    let mut player = server.client(addr(1, 1000), 1);
    run(&mut server, &mut [&mut player], 10);
    for datagram in [crashing_prefix(), short_with_long_sequence()] {
        let mut d = datagram.clone();
        assert!(matches!(player.intake.receive(SERVER_ADDR, &mut d, &mut player.renet), Err(Refused::Datagram(_))));
    }
    let mut from_elsewhere = vec![0x05; 40];
    assert_eq!(
        player.intake.receive(addr(66, 1), &mut from_elsewhere, &mut player.renet),
        Err(Refused::Datagram(DatagramRefusal::NotFromServer))
    );
    assert!(plays(&mut server, &mut player, 1), "the player still plays");
}

#[test]
fn a_client_sending_refused_payloads_is_disconnected() {
    let mut server = MemoryServer::new();
    let mut attacker = RawClient::connected(&mut server, addr(3, 3000), 3);
    for _ in 0..25 {
        let d = attacker.seal(&slice_packet(0, 9, 2));
        let _ = server.deliver(attacker.addr, &d);
    }
    server.frame();
    assert!(!server.renet.is_connected(3), "disconnected after the 21st refused payload");
    assert_eq!(server.intake.stats().expelled, 1);
}

/// A frame's messages on every channel, and renet's acks, travel in one datagram each way; a payload that
/// is not a whole bundle never reaches renet, counts as a refused payload, and the player plays on.
#[test]
fn a_frame_is_one_datagram_each_way_and_a_bad_bundle_reaches_nothing() {
    let mut server = MemoryServer::new();
    let mut player = server.client(addr(1, 1000), 1);
    run(&mut server, &mut [&mut player], 10);
    assert!(player.renet.is_connected());
    // Both sides have something on all three of renet's default channels, and acks to give.
    let channels =
        [DefaultChannel::ReliableOrdered, DefaultChannel::ReliableUnordered, DefaultChannel::Unreliable].map(u8::from);
    for channel in channels {
        server.renet.send_message(1, channel, vec![1; 100]);
        player.renet.send_message(channel, vec![2; 100]);
    }
    server.frame();
    assert_eq!(server.sent.len(), 1, "the server's frame: one datagram");
    let (_, down) = server.sent.pop().unwrap();
    player.frame(vec![down]);
    assert_eq!(player.sent.len(), 1, "the player's frame: one datagram");
    assert_eq!(server.deliver(player.addr, &player.sent.pop().unwrap()), Ok(()));
    for channel in channels {
        assert_eq!(server.renet.receive_message(1, channel).as_deref(), Some(&[2; 100][..]), "channel {channel}");
        assert_eq!(player.renet.receive_message(channel).as_deref(), Some(&[1; 100][..]), "channel {channel}");
    }

    let mut attacker = RawClient::connected(&mut server, addr(3, 3000), 3);
    let whole = heist_transport::bundle::single(&[0x03, 0, 0]);
    for (bundle, why) in [(&whole[..whole.len() - 1], "longer than"), (&[0, 0, 7][..], "empty packet")] {
        let refused = server.deliver(attacker.addr, &attacker.seal_bundle(bundle));
        assert!(
            matches!(refused, Err(Refused::Payload(PayloadRefusal::BadBundle(w))) if w.contains(why)),
            "{refused:?}"
        );
    }
    assert_eq!(server.intake.stats().refused_payloads, 2);
    assert!(plays(&mut server, &mut player, 1), "the player still plays");
}

/// What an attacker does to the server in one step.
#[derive(Clone, Debug)]
enum Attack {
    /// Random bytes from an unknown address.
    Unknown(Vec<u8>),
    /// Random bytes from the pending attacker's address.
    FromPending(Vec<u8>),
    /// Random bytes from the connected attacker's (or the player's) address.
    FromConnected(bool, Vec<u8>),
    /// A real datagram of the player, mutated, from the player's address.
    Mutated(usize, Vec<(usize, u8)>, Option<usize>),
    /// Random renet bytes sealed with the connected attacker's key: renet's parser sees them.
    Sealed(Vec<u8>),
    /// A slice header with chosen numbers and a short or full payload, sealed.
    Slice(u8, u64, u64, u64, bool),
}

fn bytes() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        proptest::collection::vec(any::<u8>(), 0..64),
        proptest::collection::vec(any::<u8>(), 0..1500),
        // Headers that pass the size check with every prefix.
        (any::<u8>(), proptest::collection::vec(any::<u8>(), 17..40)).prop_map(|(p, mut rest)| {
            rest.insert(0, p);
            rest
        }),
    ]
}

fn attack() -> impl Strategy<Value = Attack> {
    prop_oneof![
        bytes().prop_map(Attack::Unknown),
        bytes().prop_map(Attack::FromPending),
        (any::<bool>(), bytes()).prop_map(|(p, b)| Attack::FromConnected(p, b)),
        (0..64usize, proptest::collection::vec((0..1400usize, any::<u8>()), 0..4), proptest::option::of(0..1400usize))
            .prop_map(|(i, flips, cut)| Attack::Mutated(i, flips, cut)),
        proptest::collection::vec(any::<u8>(), 0..1200).prop_map(Attack::Sealed),
        (0..5u8, 0..100u64, 0..40u64, 0..40u64, any::<bool>()).prop_map(|(c, m, i, n, f)| Attack::Slice(c, m, i, n, f)),
    ]
}

/// A renet slice with these numbers and `len` payload bytes, as renet writes it.
fn varint_slice(reliable: bool, channel: u8, message_id: u64, index: u64, count: u64, len: usize) -> Vec<u8> {
    let mut buf = vec![0u8; 64 + len];
    let mut b = octets::OctetsMut::with_slice(&mut buf);
    b.put_u8(if reliable { 2 } else { 3 }).unwrap();
    b.put_varint(5).unwrap();
    b.put_u8(channel).unwrap();
    b.put_varint(message_id).unwrap();
    b.put_varint(index).unwrap();
    b.put_varint(count).unwrap();
    b.put_varint(len as u64).unwrap();
    b.put_bytes(&vec![0x5A; len]).unwrap();
    let end = b.off();
    buf.truncate(end);
    buf
}

#[test]
fn random_and_mutated_datagrams_never_stop_a_player_from_joining_and_playing() {
    let config = Config { cases: 2000, failure_persistence: None, ..Config::default() };
    let mut runner = TestRunner::new_with_rng(config, TestRng::deterministic_rng(RngAlgorithm::ChaCha));
    let attacks = proptest::collection::vec(attack(), 1..40);
    runner
        .run(&attacks, |attacks| {
            let mut server = MemoryServer::new();
            let mut player = server.client(addr(1, 1000), 1);
            run(&mut server, &mut [&mut player], 10);
            // The player's own datagrams, to mutate.
            player.renet.send_message(DefaultChannel::ReliableOrdered, vec![5; 300]);
            player.frame(Vec::new());
            let mut real = std::mem::take(&mut player.sent);
            run(&mut server, &mut [&mut player], 3);
            real.extend(std::mem::take(&mut player.sent));
            let mut pending = RawClient::pending(&mut server, addr(2, 2000), 2);
            let mut connected = RawClient::connected(&mut server, addr(3, 3000), 3);
            for attack in attacks {
                let _ = match attack {
                    Attack::Unknown(b) => server.deliver(addr(9, 9000), &b),
                    Attack::FromPending(b) => server.deliver(pending.addr, &b),
                    Attack::FromConnected(as_player, b) => {
                        server.deliver(if as_player { player.addr } else { connected.addr }, &b)
                    }
                    Attack::Mutated(i, flips, cut) => {
                        let Some(mut d) = real.get(i % real.len().max(1)).cloned() else { continue };
                        let len = d.len().max(1);
                        for (at, v) in flips {
                            if let Some(byte) = d.get_mut(at % len) {
                                *byte ^= v;
                            }
                        }
                        if let Some(n) = cut {
                            d.truncate(n);
                        }
                        server.deliver(player.addr, &d)
                    }
                    Attack::Sealed(b) => {
                        let d = connected.seal(&b);
                        server.deliver(connected.addr, &d)
                    }
                    Attack::Slice(c, m, i, n, full) => {
                        let d = connected.seal(&varint_slice(c % 2 == 0, c / 2, m, i, n, if full { 1200 } else { 7 }));
                        server.deliver(connected.addr, &d)
                    }
                };
                let _ = pending.netcode.update(heist_transport::memory::FRAME);
                server.frame();
            }
            prop_assert!(plays(&mut server, &mut player, 1), "the connected player plays on");
            let mut newcomer = server.client(addr(4, 4000), 4);
            run(&mut server, &mut [&mut newcomer, &mut player], 10);
            prop_assert!(newcomer.renet.is_connected(), "a new player connects");
            prop_assert!(plays(&mut server, &mut newcomer, 4), "and plays");
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn the_intake_refuses_a_sequence_that_would_overflow_the_replay_window() {
    let mut server = MemoryServer::new();
    let connected = RawClient::connected(&mut server, addr(3, 3000), 3);
    assert_eq!(
        server.deliver(connected.addr, &huge_sequence()),
        Err(Refused::Datagram(DatagramRefusal::SequenceOutOfRange))
    );
}
