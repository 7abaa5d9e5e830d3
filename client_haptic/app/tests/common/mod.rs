//! Helpers for the terminal tests: the client as a screen-reader user runs it, and reading what it says.
#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The client as a screen-reader user runs it: `args` then `--headless --audio memory`, `RUST_LOG` unset;
/// its stdin to type into and its stdout read line by line on a thread (stderr stays piped for the caller).
pub fn headless(args: &[&str]) -> (Child, ChildStdin, mpsc::Receiver<String>) {
    headless_with_cache(args, &std::env::temp_dir().join(format!("phantom-terminal-{}", std::process::id())))
}

/// [`headless`] with its seat cache (`XDG_CACHE_HOME`) in `cache`.
pub fn headless_with_cache(args: &[&str], cache: &std::path::Path) -> (Child, ChildStdin, mpsc::Receiver<String>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_client_haptic"))
        .args(args)
        .args(["--headless", "--audio", "memory"])
        .env_remove("RUST_LOG")
        .env("XDG_CACHE_HOME", cache)
        .env("XDG_CONFIG_HOME", cache.join("config"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("client_haptic runs");
    let stdin = child.stdin.take().expect("stdin");
    let stdout = child.stdout.take().expect("stdout");
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    (child, stdin, rx)
}

/// Waits up to `within` for a line starting with `text`, keeping every line in `lines`.
pub fn hear(rx: &mpsc::Receiver<String>, lines: &mut Vec<String>, text: &str, within: Duration) -> bool {
    let deadline = Instant::now() + within;
    while Instant::now() < deadline {
        if let Ok(line) = rx.recv_timeout(Duration::from_millis(100)) {
            let found = line.starts_with(text);
            lines.push(line);
            if found {
                return true;
            }
        }
    }
    false
}

/// Waits for `child` to exit, killing it after `limit`.
pub fn wait(child: &mut Child, limit: Duration) -> Option<std::process::ExitStatus> {
    let deadline = Instant::now() + limit;
    while Instant::now() < deadline {
        if let Ok(Some(status)) = child.try_wait() {
            return Some(status);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    None
}

/// A host on its own thread: a loopback server (heists of `time_limit_s`) and, once Phantom is in, a Vive
/// bot that asks for another round after the first. Stepped at about 60 Hz of wall-clock time until
/// `stop` is set, its game loop standing still while `stall` is set (the token endpoint, on its own
/// thread, still answers: a hung server process or a dead network); sends the join code, then the
/// server's log at the end.
pub fn host_with_a_vive_bot(
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    stall: std::sync::Arc<std::sync::atomic::AtomicBool>,
    time_limit_s: f32,
) -> (std::net::SocketAddr, String, std::thread::JoinHandle<Vec<String>>) {
    use heist_server::{ServerOptions, build_server};
    use heist_shared::protocol::Role;
    use std::sync::atomic::Ordering;
    let (tx, rx) = mpsc::channel();
    let host = std::thread::spawn(move || {
        let mut options = ServerOptions::local_test(12);
        options.game.time_limit_s = Some(time_limit_s);
        let mut server = build_server(options).expect("server starts");
        let tokens = server.tokens.as_ref().expect("secure");
        tx.send((tokens.addr, server.join_code().expect("a host session").code)).expect("the test waits");
        let mut vive: Option<bevy::app::App> = None;
        let deadline = Instant::now() + Duration::from_secs(150);
        while !stop.load(Ordering::Relaxed) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(16));
            if stall.load(Ordering::Relaxed) {
                continue;
            }
            server.update();
            if vive.is_none() && server.game().is_present(Role::Phantom) {
                let app = heist_server::demo::join(&server, Role::Vive, |app| {
                    app.add_plugins(heist_bots::ViveBotPlugin { style: heist_bots::ViveStyle::Idle })
                        .insert_resource(heist_bots::Rounds(2));
                })
                .expect("the Vive bot joins");
                vive = Some(app);
            }
            if let Some(v) = vive.as_mut() {
                v.update();
            }
        }
        server.log().to_vec()
    });
    let (addr, code) = rx.recv_timeout(Duration::from_secs(30)).expect("the host starts");
    (addr, code, host)
}
