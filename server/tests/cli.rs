//! The server binary as a user meets it: bad input gives a clear message, never a panic.

#![allow(clippy::unwrap_used)] // helpers outside the #[test] fns unwrap too: a panic fails the test

use std::process::Command;

fn write(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("heist-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn the_server_binary_refuses_a_bad_level_with_a_clear_message() {
    let path = write(
        "bin.ron",
        &include_str!("../../assets/levels/museum.ron").replace("time_limit_s: 600.0", "time_limit_s: -5.0"),
    );
    let out = Command::new(env!("CARGO_BIN_EXE_heist-server"))
        .args(["demo", "--level"])
        .arg(&path)
        .output()
        .expect("the server binary runs");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("bin.ron") && stderr.contains("time_limit_s") && stderr.contains("positive"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn the_demo_prints_a_result_line() {
    let out = Command::new(env!("CARGO_BIN_EXE_heist-server"))
        .args(["demo", "--seed", "1", "--vive", "reckless"])
        .output()
        .expect("the server binary runs");
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let last = stdout.lines().last().unwrap_or_default();
    assert!(last.starts_with("RESULT: Lost(caught) after "), "{stdout}");
    assert!(stdout.contains("phase: Heist"));
}

#[test]
fn a_sweep_tallies_every_seed() {
    let out = Command::new(env!("CARGO_BIN_EXE_heist-server"))
        .args(["sweep", "--from", "1", "--to", "2", "--vive", "reckless"])
        .output()
        .expect("the server binary runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("seed    1: RESULT: Lost(caught)"), "{stdout}");
    assert!(stdout.contains("seed    2: RESULT: Lost(caught)"), "{stdout}");
    assert_eq!(
        stdout.lines().last(),
        Some("won 0 of 2 (0.0%), caught 2, other losses 0; winning seeds: []"),
        "{stdout}"
    );

    let bad =
        Command::new(env!("CARGO_BIN_EXE_heist-server")).args(["sweep", "--from", "5", "--to", "2"]).output().unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--from 5 is after --to 2"));
}

/// Reads `child`'s stdout line by line on a thread, so the test can wait for a line with a deadline.
fn lines_of(stream: impl std::io::Read + Send + 'static) -> std::sync::mpsc::Receiver<String> {
    use std::io::BufRead as _;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stream).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

/// Waits for `child` to exit, killing it after `limit`.
fn wait_for(child: &mut std::process::Child, limit: std::time::Duration) -> Option<std::process::ExitStatus> {
    let deadline = std::time::Instant::now() + limit;
    while std::time::Instant::now() < deadline {
        if let Ok(Some(status)) = child.try_wait() {
            return Some(status);
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    let _ = child.kill();
    None
}

/// A `heist-server --log-format json host` process on a free loopback port, as an operator starts one.
struct Host {
    child: std::process::Child,
    /// `127.0.0.1:PORT`, UDP and TCP alike.
    addr: String,
    port: u16,
    /// Its stdout, line by line.
    out: std::sync::mpsc::Receiver<String>,
    /// Its log (stderr), line by line.
    log: std::sync::mpsc::Receiver<String>,
    /// The join code it printed.
    code: String,
}

/// Starts `heist-server --log-format json COMMAND --bind ADDR ARGS…` on a free loopback port; returns
/// the process, its address, port, stdout and stderr, line by line.
#[allow(clippy::type_complexity)]
fn serve_on_a_free_port(
    command: &str,
    args: &[&str],
) -> (std::process::Child, String, u16, std::sync::mpsc::Receiver<String>, std::sync::mpsc::Receiver<String>) {
    use std::process::Stdio;
    let port = std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let addr = format!("127.0.0.1:{port}");
    let mut child = Command::new(env!("CARGO_BIN_EXE_heist-server"))
        .args(["--log-format", "json", command, "--bind", &addr])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = lines_of(child.stdout.take().unwrap());
    let log = lines_of(child.stderr.take().unwrap());
    (child, addr, port, out, log)
}

/// Starts `host --bind ADDR ARGS…` and waits (at most 20 s) for the join code it prints.
fn host(args: &[&str]) -> Host {
    use std::time::{Duration, Instant};
    let (child, addr, port, out, log) = serve_on_a_free_port("host", args);
    let deadline = Instant::now() + Duration::from_secs(20);
    let code = loop {
        let line =
            out.recv_timeout(deadline.saturating_duration_since(Instant::now())).expect("the host prints its code");
        if let Some(rest) = line.strip_prefix("join code: ") {
            break rest.split_whitespace().next().unwrap().to_owned();
        }
    };
    Host { child, addr, port, out, log, code }
}

#[test]
fn a_hosted_session_plays_two_rounds_for_two_bot_processes_logs_them_as_json_and_ends() {
    use std::process::Stdio;
    use std::time::Duration;
    let bin = env!("CARGO_BIN_EXE_heist-server");
    let Host { child: mut host, addr, out, log, code, .. } = host(&["--time-limit", "4", "--idle-end", "30"]);
    let cache = std::env::temp_dir().join(format!("heist-cli-seats-{}-rounds", std::process::id()));
    let bot = |role: &str| {
        Command::new(bin)
            .args(["join", &addr, "--code", &code, "--role", role, "--vive", "idle", "--rounds", "2"])
            .env("XDG_CACHE_HOME", &cache)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let mut bots = [bot("vive"), bot("phantom")];
    // Two rounds of 4 s, then both bots leave and the empty session ends: the host exits by itself.
    let status = wait_for(&mut host, Duration::from_secs(60));
    for b in &mut bots {
        let _ = wait_for(b, Duration::from_secs(5));
    }
    assert!(status.is_some_and(|s| s.success()), "the host exits 0 once the session is over: {status:?}");
    let printed: Vec<String> = out.try_iter().collect();
    assert_eq!(printed.last().map(String::as_str), Some("the session is over"), "{printed:?}");

    let events: Vec<serde_json::Value> = log
        .try_iter()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(&l).ok())
        .filter(|v| v["target"] == "session")
        .collect();
    let names: Vec<&str> = events.iter().filter_map(|e| e["event"].as_str()).collect();
    let count = |n: &str| names.iter().filter(|&&x| x == n).count();
    assert_eq!(count("session_created"), 1, "{names:?}");
    assert_eq!(count("player_joined"), 2, "{names:?}");
    assert_eq!(count("result"), 2, "two rounds were played: {names:?}");
    assert_eq!(count("round_started"), 1, "{names:?}");
    assert_eq!(count("player_left"), 2, "both bots left on purpose after the last round: {names:?}");
    assert_eq!(count("session_ended"), 1, "{names:?}");
    let id = events[0]["session"].as_str().unwrap();
    assert!(events.iter().all(|e| e["session"] == id), "one session id throughout");
    assert!(!events.iter().any(|e| e.to_string().contains(&code)), "the join code is never logged");
    let results: Vec<_> = events.iter().filter(|e| e["event"] == "result").collect();
    assert!(results.iter().all(|r| r["reason"] == "time" && r["won"] == false), "{results:?}");
    assert_ne!(results[0]["seed"], results[1]["seed"], "each round has its own seed");
    let _ = std::fs::remove_dir_all(cache);
}

#[test]
fn a_bot_process_killed_mid_heist_and_started_again_takes_its_seat_back() {
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let bin = env!("CARGO_BIN_EXE_heist-server");
    let Host { child: mut host, addr, port, log, code, .. } = host(&["--time-limit", "120", "--idle-end", "5"]);
    // Each bot has its own seat cache, as two players on two machines would.
    let cache = |role: &str| std::env::temp_dir().join(format!("heist-cli-seats-{}-{role}", std::process::id()));
    let bot = |role: &str| {
        let mut child = Command::new(bin)
            .args(["join", &addr, "--code", &code, "--role", role, "--vive", "idle"])
            .env("XDG_CACHE_HOME", cache(role))
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let lines = lines_of(child.stdout.take().unwrap());
        (child, lines)
    };
    let first_line = |lines: &std::sync::mpsc::Receiver<String>| lines.recv_timeout(Duration::from_secs(20)).ok();
    let (mut vive, vive_out) = bot("vive");
    let (mut phantom, phantom_out) = bot("phantom");
    assert_eq!(first_line(&vive_out), Some(format!("joined {addr} as Vive")));
    assert_eq!(first_line(&phantom_out), Some(format!("joined {addr} as Phantom")));
    let seat_file = cache("vive").join("phantom-heist").join("seats").join(format!("127_0_0_1-{port}-vive.seat"));
    let stored = Instant::now();
    while !seat_file.exists() && stored.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(seat_file.exists(), "the bot kept its seat ticket in {}", seat_file.display());

    // The Vive bot is killed (no goodbye) and started again: it takes its seat back with the cached ticket.
    vive.kill().unwrap();
    let _ = vive.wait();
    let (mut again, again_out) = bot("vive");
    assert_eq!(first_line(&again_out), Some(format!("took the Vive seat back at {addr}")));
    let resumed = Instant::now();
    let mut events = Vec::new();
    while !events.iter().any(|e: &serde_json::Value| e["event"] == "player_resumed")
        && resumed.elapsed() < Duration::from_secs(10)
    {
        if let Ok(line) = log.recv_timeout(Duration::from_millis(200))
            && let Ok(v) = serde_json::from_str::<serde_json::Value>(&line)
            && v["target"] == "session"
        {
            events.push(v);
        }
    }
    let back = events.iter().find(|e| e["event"] == "player_resumed").expect("the host logs the resume");
    assert_eq!(back["role"], "vive");
    assert!(!events.iter().any(|e| e["event"] == "player_joined" && e["role"] == "vive" && e["game_time_s"] != 0.0));
    for child in [&mut again, &mut phantom, &mut host] {
        let _ = child.kill();
        let _ = child.wait();
    }
    for role in ["vive", "phantom"] {
        let _ = std::fs::remove_dir_all(cache(role));
    }
}

#[test]
fn a_served_server_hosts_two_sessions_bot_processes_created_and_each_ends_on_its_own() {
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let bin = env!("CARGO_BIN_EXE_heist-server");
    let (mut serve, addr, _, out, log) = serve_on_a_free_port("serve", &["--max-sessions", "2", "--time-limit", "3"]);
    let deadline = Instant::now() + Duration::from_secs(20);
    while !out
        .recv_timeout(deadline.saturating_duration_since(Instant::now()))
        .expect("serve starts")
        .contains("serving")
    {}
    let cache = std::env::temp_dir().join(format!("heist-cli-seats-{}-serve", std::process::id()));
    let bot = |args: &[&str], role: &str, name: &str| {
        Command::new(bin)
            .args(["join", &addr])
            .args(args)
            .args(["--role", role, "--vive", "idle"])
            .env("XDG_CACHE_HOME", cache.join(name))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    // Two Vive bots each create a session and print its code; a Phantom bot joins each with it.
    let mut bots = Vec::new();
    let mut codes = Vec::new();
    for n in 0..2 {
        let mut creator = bot(&["--create"], "vive", &format!("creator{n}"));
        let printed = lines_of(creator.stdout.take().unwrap());
        let line = printed.recv_timeout(Duration::from_secs(20)).expect("the creator prints the code");
        let code = line.split("join code: ").nth(1).expect("a code").trim().to_owned();
        bots.push(bot(&["--code", &code], "phantom", &format!("partner{n}")));
        bots.push(creator);
        codes.push(code);
    }
    assert_ne!(codes[0], codes[1], "each session has its own code");
    // A third creator finds the server full, on one line.
    let full = Command::new(bin).args(["join", &addr, "--create", "--role", "vive"]).output().unwrap();
    let err = String::from_utf8_lossy(&full.stderr);
    assert!(!full.status.success() && err.contains("hosts 2 sessions already"), "{err}");
    // Each 3 s heist ends on time, the bots leave, each session ends; the server runs on.
    for b in &mut bots {
        assert!(wait_for(b, Duration::from_secs(60)).is_some(), "a bot leaves after its heist");
    }
    let mut names = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(20);
    while names.iter().filter(|(n, _): &&(String, String)| n == "session_ended").count() < 2
        && Instant::now() < deadline
    {
        if let Ok(line) = log.recv_timeout(Duration::from_millis(200))
            && let Ok(v) = serde_json::from_str::<serde_json::Value>(&line)
            && v["target"] == "session"
        {
            names
                .push((v["event"].as_str().unwrap_or("?").to_owned(), v["session"].as_str().unwrap_or("?").to_owned()));
        }
    }
    let sessions: std::collections::HashSet<&String> = names.iter().map(|(_, s)| s).collect();
    let count = |e: &str| names.iter().filter(|(n, _)| n == e).count();
    assert_eq!(sessions.len(), 2, "two sessions in the log: {names:?}");
    assert_eq!((count("session_created"), count("player_joined"), count("result")), (2, 4, 2), "{names:?}");
    assert_eq!(count("session_ended"), 2, "{names:?}");
    assert!(serve.try_wait().unwrap().is_none(), "serve runs on after its sessions ended");
    let _ = serve.kill();
    let _ = serve.wait();
    let _ = std::fs::remove_dir_all(cache);
}

#[test]
fn load_plays_bot_pairs_in_sessions_of_their_own_and_ends_with_one_json_line_of_figures() {
    let out = Command::new(env!("CARGO_BIN_EXE_heist-server"))
        .args(["load", "--sessions", "3", "--seconds", "2", "--json"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    let last: serde_json::Value = serde_json::from_str(text.lines().last().unwrap_or_default()).expect("JSON last");
    assert_eq!(
        (last["sessions"].as_u64(), last["players"].as_u64(), last["ticks"].as_u64()),
        (Some(3), Some(6), Some(120))
    );
    let number = |k: &str| last[k].as_f64().unwrap_or_else(|| panic!("{k} in {last}"));
    for k in ["session_tick_us_median", "session_tick_us_p99", "tick_ms_p99"] {
        assert!(number(k) > 0.0, "{k}: {last}");
    }
    assert!(number("session_tick_us_median") <= number("session_tick_us_p99"), "{last}");
    // Every client moves (Vive 60 moves a second) and is replicated to: bytes both ways, within reason.
    for k in ["client_bytes_per_s_up", "client_bytes_per_s_down"] {
        assert!((500.0..100_000.0).contains(&number(k)), "{k}: {last}");
    }
    assert!(text.contains("server CPU per session-tick"), "{text}");
}
