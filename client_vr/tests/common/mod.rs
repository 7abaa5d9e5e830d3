//! Helpers for the Vive client's tests: a stepped client app joined to a test server, and a loopback
//! UDP relay that delays packets.
#![allow(dead_code)]

use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

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
        Command::XrCheck => unreachable!(),
    }
}

/// The real headless Vive client app, joined to `server` through its token endpoint, its clock stepped
/// one tick per update; `setup` adds test systems before it connects.
pub fn vive_client(server: &HostedServer, args: &JoinArgs, setup: impl FnOnce(&mut App)) -> App {
    let token = heist_server::demo::token(server, Role::Vive).expect("token");
    let mut app = client_vr::cli::app(args, &Mode::Headless).expect("the app builds");
    app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(1.0 / TICK_HZ)));
    setup(&mut app);
    app.finish();
    app.cleanup();
    heist_client::connect(&mut app, token).expect("connects");
    app
}

/// How a relayed link behaves.
#[derive(Clone, Copy, Debug)]
pub struct Link {
    /// Base delay each way.
    pub delay: Duration,
    /// Extra random delay, up to.
    pub jitter: Duration,
    /// Probability a packet is lost.
    pub loss: f64,
}

/// A loopback UDP relay: clients send to [`Relay::addr`]; every packet, both ways, is held `delay`.
pub struct Relay {
    /// Where clients send.
    pub addr: SocketAddr,
    front: Option<UdpSocket>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Relay {
    /// Binds the relay's front socket (the address to advertise to clients).
    pub fn bind() -> Self {
        let front = UdpSocket::bind("127.0.0.1:0").expect("relay binds");
        front.set_nonblocking(true).expect("nonblocking");
        let addr = front.local_addr().expect("address");
        Self { addr, front: Some(front), stop: Arc::new(AtomicBool::new(false)), thread: None }
    }

    /// Starts relaying to `server` with `delay` each way (see [`Relay::start_with`]).
    pub fn start(&mut self, server: SocketAddr, delay: Duration) {
        self.start_with(server, Link { delay, jitter: Duration::ZERO, loss: 0.0 });
    }

    /// Starts relaying to `server` through `link`: each packet is held `delay` plus a uniform
    /// random extra of up to `jitter` (so packets can overtake each other), and dropped with probability
    /// `loss` — from a fixed seed, so a run repeats.
    pub fn start_with(&mut self, server: SocketAddr, link: Link) {
        let Link { delay, jitter, loss } = link;
        let front = self.front.take().expect("started once");
        let flag = self.stop.clone();
        self.thread = Some(std::thread::spawn(move || {
            // One upstream socket per client, so the server sees each client at its own address.
            let mut clients: Vec<(SocketAddr, UdpSocket)> = Vec::new();
            let mut queue: Vec<(Instant, Vec<u8>, usize, bool)> = Vec::new(); // (due, bytes, client, upstream?)
            let mut rng: u64 = 0x9E37_79B9_7F4A_7C15;
            let mut roll = move || {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                (rng >> 11) as f64 / (1u64 << 53) as f64
            };
            let mut hold = move |queue: &mut Vec<(Instant, Vec<u8>, usize, bool)>, bytes: &[u8], i: usize, up: bool| {
                if roll() < loss {
                    return;
                }
                let extra = jitter.mul_f64(roll());
                queue.push((Instant::now() + delay + extra, bytes.to_vec(), i, up));
            };
            let mut buf = [0u8; 2048];
            let started = Instant::now();
            while !flag.load(Ordering::Relaxed) && started.elapsed() < Duration::from_secs(600) {
                while let Ok((n, from)) = front.recv_from(&mut buf) {
                    let i = match clients.iter().position(|(a, _)| *a == from) {
                        Some(i) => i,
                        None => {
                            let up = UdpSocket::bind("127.0.0.1:0").expect("upstream binds");
                            up.set_nonblocking(true).expect("nonblocking");
                            clients.push((from, up));
                            clients.len() - 1
                        }
                    };
                    hold(&mut queue, &buf[..n], i, true);
                }
                for (i, (_, up)) in clients.iter().enumerate() {
                    while let Ok((n, _)) = up.recv_from(&mut buf) {
                        hold(&mut queue, &buf[..n], i, false);
                    }
                }
                let now = Instant::now();
                queue.sort_by_key(|p| p.0);
                let due = queue.iter().take_while(|p| p.0 <= now).count();
                for (_, bytes, i, upstream) in queue.drain(..due) {
                    let (client, up) = &clients[i];
                    let _ = if upstream { up.send_to(&bytes, server) } else { front.send_to(&bytes, *client) };
                }
                std::thread::sleep(Duration::from_micros(300));
            }
        }));
    }
}

impl Drop for Relay {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
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
