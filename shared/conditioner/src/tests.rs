use std::net::UdpSocket;
use std::time::Duration;

use super::*;

fn socket() -> UdpSocket {
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    s.set_nonblocking(true).unwrap();
    s
}

/// Gives the kernel a moment to deliver a loopback datagram, then reads all waiting.
fn received(s: &UdpSocket) -> Vec<(Vec<u8>, std::net::SocketAddr)> {
    std::thread::sleep(Duration::from_millis(20));
    let mut out = Vec::new();
    let mut buf = [0u8; 2048];
    while let Ok((n, from)) = s.recv_from(&mut buf) {
        out.push((buf[..n].to_vec(), from));
    }
    out
}

const MS: Duration = Duration::from_millis(1);

fn relay_to(server: &UdpSocket, conditions: Conditions, seed: u64) -> SteppedRelay {
    let mut relay = SteppedRelay::bind(conditions, seed).unwrap();
    relay.forward_to(server.local_addr().unwrap());
    relay
}

#[test]
fn a_stepped_relay_holds_each_datagram_for_the_latency_each_way() {
    let server = socket();
    let mut relay = relay_to(&server, Conditions::delay(200 * MS), 1);
    let client = socket();
    client.send_to(b"up", relay.addr()).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    relay.advance(MS).unwrap();
    relay.advance(198 * MS).unwrap();
    assert!(received(&server).is_empty(), "held at 199 ms");
    relay.advance(MS).unwrap();
    let got = received(&server);
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].0, b"up");
    // The answer goes back through the client's own upstream address, and is held as long.
    server.send_to(b"down", got[0].1).unwrap();
    std::thread::sleep(Duration::from_millis(20));
    relay.advance(MS).unwrap();
    assert!(received(&client).is_empty());
    relay.advance(200 * MS).unwrap();
    assert_eq!(received(&client).iter().map(|(b, _)| b.clone()).collect::<Vec<_>>(), vec![b"down".to_vec()]);
    assert_eq!(relay.stats().up.passed, 1);
    assert_eq!(relay.stats().down.bytes, 4);
}

#[test]
fn the_poor_preset_loses_about_a_tenth_and_spreads_arrivals_over_the_jitter() {
    let server = socket();
    let mut relay = relay_to(&server, Conditions::POOR, 7);
    let client = socket();
    // Few enough that the receiving socket's kernel buffer holds them all.
    let n = 400;
    for i in 0..n {
        client.send_to(&(i as u32).to_be_bytes(), relay.addr()).unwrap();
        if i % 100 == 99 {
            std::thread::sleep(Duration::from_millis(10));
            relay.advance(Duration::ZERO).unwrap();
        }
    }
    std::thread::sleep(Duration::from_millis(20));
    relay.advance(Duration::ZERO).unwrap();
    let stats = relay.stats();
    assert_eq!(stats.up.dropped + relay.held() as u64, n as u64, "every datagram was held or dropped");
    assert!((25..=60).contains(&stats.up.dropped), "{} of {n} lost", stats.up.dropped);
    relay.advance(199 * MS).unwrap();
    assert!(received(&server).is_empty(), "none before the latency");
    relay.advance(15 * MS).unwrap();
    let early = received(&server).len() as f64;
    relay.advance(20 * MS).unwrap();
    let all = early + received(&server).len() as f64;
    let kept = (n - stats.up.dropped as usize) as f64;
    assert_eq!(all, kept, "all arrived within latency + jitter");
    assert!((0.3..=0.7).contains(&(early / all)), "half arrive in the first half of the jitter: {early}/{all}");
}

#[test]
fn the_same_seed_drops_the_same_datagrams() {
    let run = |seed| {
        let server = socket();
        let mut relay = relay_to(&server, Conditions::POOR, seed);
        let client = socket();
        for i in 0..200u32 {
            client.send_to(&i.to_be_bytes(), relay.addr()).unwrap();
        }
        std::thread::sleep(Duration::from_millis(20));
        relay.advance(Duration::from_secs(1)).unwrap();
        let mut got: Vec<Vec<u8>> = received(&server).into_iter().map(|(b, _)| b).collect();
        got.sort();
        got
    };
    assert_eq!(run(3), run(3));
    assert_ne!(run(3), run(4));
}

#[test]
fn a_threaded_relay_delays_in_wall_clock_time() {
    let server = socket();
    let mut relay = Relay::bind(Conditions::delay(100 * MS), 1).unwrap();
    relay.start(server.local_addr().unwrap()).unwrap();
    let client = socket();
    let sent = std::time::Instant::now();
    client.send_to(b"x", relay.addr).unwrap();
    let mut buf = [0u8; 16];
    let mut arrived = None;
    while sent.elapsed() < Duration::from_secs(5) && arrived.is_none() {
        if server.recv_from(&mut buf).is_ok() {
            arrived = Some(sent.elapsed());
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    let arrived = arrived.expect("relayed");
    assert!(arrived >= 100 * MS, "{arrived:?}");
    assert_eq!(relay.stop().up.passed, 1);
}
