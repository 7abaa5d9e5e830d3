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
fn the_demo_trace_shows_each_goal_the_vive_bot_picks_and_its_decisions() {
    let out = Command::new(env!("CARGO_BIN_EXE_heist-server"))
        .args(["demo", "--seed", "1", "--vive", "reckless"])
        .env("HEIST_TRACE", "1")
        .output()
        .expect("the server binary runs");
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let goals: Vec<&str> = stdout.lines().filter(|l| l.contains(" Vive bot: ")).collect();
    assert!(goals.first().is_some_and(|l| l.starts_with("  t=0.0 Vive bot: ")), "{stdout}");
    assert!(
        goals.iter().all(|l| l.ends_with("(then rush_if_reckless)")
            && ["break the case at (", "take item ", "bring item ", "go to ("].iter().any(|g| l.contains(g))),
        "{goals:?}"
    );
    assert!(goals.iter().any(|l| l.contains("break the case at (")), "{goals:?}");
    assert!(stdout.lines().any(|l| l.contains(" vive=(") && l.contains(" rush_if_reckless | Bruno(")), "{stdout}");
}

#[test]
fn a_sweep_tallies_every_seed() {
    let sweep = |jobs: &str| {
        Command::new(env!("CARGO_BIN_EXE_heist-server"))
            .args(["sweep", "--from", "1", "--to", "3", "--vive", "reckless", "--jobs", jobs])
            .output()
            .expect("the server binary runs")
    };
    let out = sweep("2");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    // Two heists at a time, the lines still in seed order.
    let at = |seed: &str| stdout.find(&format!("seed    {seed}: RESULT: Lost(caught)")).expect(&stdout);
    assert!(at("1") < at("2") && at("2") < at("3"), "{stdout}");
    let one_at_a_time = sweep("1");
    assert_eq!(String::from_utf8_lossy(&one_at_a_time.stdout), stdout, "the same heists, whatever runs beside them");
    assert!(stdout.contains("\nnormal: won 0 of 3 (0.0%), caught 3, other losses 0; winning seeds: []\n"), "{stdout}");
    assert!(stdout.contains("\n  caught by: "), "the causes of the losses: {stdout}");
    assert!(
        stdout.contains("by Bruno in the ")
            || stdout.contains("by Clara in the ")
            || stdout.contains("by Dmitri in the "),
        "{stdout}"
    );
    assert!(stdout.contains("\n  bot's time: rush_if_reckless 100%; carrying "), "where the time went: {stdout}");

    // A level file's own difficulty table is what the sweep measures: here its normal heist lasts 6 s.
    let short = write(
        "short.ron",
        &include_str!("../../assets/levels/museum.ron").replace(
            "    exit: (1.0, 1.0),",
            "    exit: (1.0, 1.0),\n    difficulties: (normal: Some((time_scale: 0.01))),",
        ),
    );
    let out = Command::new(env!("CARGO_BIN_EXE_heist-server"))
        .args(["sweep", "--from", "1", "--to", "1", "--level"])
        .arg(&short)
        .output()
        .expect("the server binary runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("seed    1: RESULT: Lost(time) after 6.0 s"), "the level's own 6 s: {stdout}");
    let missing = Command::new(env!("CARGO_BIN_EXE_heist-server"))
        .args(["sweep", "--level", "/nonexistent/level.ron"])
        .output()
        .unwrap();
    assert!(!missing.status.success());
    let stderr = String::from_utf8_lossy(&missing.stderr);
    assert!(stderr.contains("/nonexistent/level.ron") && stderr.lines().count() == 1, "{stderr}");

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
    serve_on_a_free_port_with(command, args, &[])
}

/// [`serve_on_a_free_port`] with environment variables.
#[allow(clippy::type_complexity)]
fn serve_on_a_free_port_with(
    command: &str,
    args: &[&str],
    envs: &[(&str, String)],
) -> (std::process::Child, String, u16, std::sync::mpsc::Receiver<String>, std::sync::mpsc::Receiver<String>) {
    use std::process::Stdio;
    let port = std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let addr = format!("127.0.0.1:{port}");
    let mut child = Command::new(env!("CARGO_BIN_EXE_heist-server"))
        .args(["--log-format", "json", command, "--bind", &addr])
        .args(args)
        .envs(envs.iter().map(|(k, v)| (k, v)))
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

/// One session per pair of idle bot processes: a Vive bot creates it (`join --create`) and a Phantom bot
/// joins with the code it prints, each bot with a seat cache of its own under `cache`. The bots, each
/// with its stdout line by line, and the codes.
#[allow(clippy::type_complexity)]
fn bot_pairs(
    addr: &str,
    cache: &std::path::Path,
    sessions: usize,
) -> (Vec<(std::process::Child, std::sync::mpsc::Receiver<String>)>, Vec<String>) {
    use std::process::Stdio;
    let bot = |args: &[&str], role: &str, name: &str| {
        let mut child = Command::new(env!("CARGO_BIN_EXE_heist-server"))
            .args(["join", addr])
            .args(args)
            .args(["--role", role, "--vive", "idle"])
            .env("XDG_CACHE_HOME", cache.join(name))
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let out = lines_of(child.stdout.take().unwrap());
        (child, out)
    };
    let (mut bots, mut codes) = (Vec::new(), Vec::new());
    for n in 0..sessions {
        let creator = bot(&["--create"], "vive", &format!("creator{n}"));
        let code = line_after(&creator.1, "join code: ", std::time::Duration::from_secs(20)).trim().to_owned();
        bots.push(bot(&["--code", &code], "phantom", &format!("partner{n}")));
        bots.push(creator);
        codes.push(code);
    }
    (bots, codes)
}

#[test]
fn a_served_server_hosts_two_sessions_bot_processes_created_and_each_ends_on_its_own() {
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
    // Two Vive bots each create a session and print its code; a Phantom bot joins each with it.
    let (mut bots, codes) = bot_pairs(&addr, &cache, 2);
    assert_ne!(codes[0], codes[1], "each session has its own code");
    // A third creator finds the server full, on one line.
    let full = Command::new(bin).args(["join", &addr, "--create", "--role", "vive"]).output().unwrap();
    let err = String::from_utf8_lossy(&full.stderr);
    assert!(!full.status.success() && err.contains("hosts 2 sessions already"), "{err}");
    // Each 3 s heist ends on time, the bots leave, each session ends; the server runs on.
    for (b, _) in &mut bots {
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
    for k in ["session_tick_us_median", "session_tick_us_p99", "tick_ms_p99", "bots_tick_ms_median"] {
        assert!(number(k) > 0.0, "{k}: {last}");
    }
    assert!(number("session_tick_us_median") <= number("session_tick_us_p99"), "{last}");
    // Every client moves (Vive 60 moves a second) and is replicated to: bytes both ways, within reason.
    for k in ["client_bytes_per_s_up", "client_bytes_per_s_down"] {
        assert!((500.0..100_000.0).contains(&number(k)), "{k}: {last}");
    }
    assert!(text.contains("server CPU per session-tick"), "{text}");
    assert!(text.contains("the bots between two server ticks"), "{text}");
}

/// `GET path` on `addr` (HTTP/1.1, one request); the status code and the body.
fn http_get(addr: &str, path: &str) -> (u16, String) {
    use std::io::{Read as _, Write as _};
    let mut stream = std::net::TcpStream::connect(addr).unwrap();
    stream.set_read_timeout(Some(std::time::Duration::from_secs(5))).unwrap();
    write!(stream, "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n").unwrap();
    let mut text = String::new();
    stream.read_to_string(&mut text).unwrap();
    let status = text.split_whitespace().nth(1).and_then(|s| s.parse().ok()).unwrap_or(0);
    let body = text.split_once("\r\n\r\n").map(|(_, b)| b.to_owned()).unwrap_or_default();
    (status, body)
}

/// Waits (at most `limit`) for a line of `lines` that contains `marker`; the part after it.
fn line_after(lines: &std::sync::mpsc::Receiver<String>, marker: &str, limit: std::time::Duration) -> String {
    let deadline = std::time::Instant::now() + limit;
    loop {
        let line = lines
            .recv_timeout(deadline.saturating_duration_since(std::time::Instant::now()))
            .unwrap_or_else(|_| panic!("no line with {marker:?} within {limit:?}"));
        if let Some((_, rest)) = line.split_once(marker) {
            return rest.to_owned();
        }
    }
}

#[test]
fn health_and_metrics_scraped_while_load_runs_count_its_sessions_players_ticks_and_bytes() {
    use heist_server::fleet::metrics::sample;
    use std::process::Stdio;
    use std::time::Duration;
    let mut load = Command::new(env!("CARGO_BIN_EXE_heist-server"))
        .args(["load", "--sessions", "3", "--seconds", "30", "--json", "--metrics", "127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let out = lines_of(load.stdout.take().unwrap());
    let addr = line_after(&out, "health and metrics on http://", Duration::from_secs(20));
    let addr = addr.split('/').next().unwrap().to_owned();
    line_after(&out, "measuring", Duration::from_secs(60));

    let (status, health) = http_get(&addr, "/healthz");
    assert_eq!((status, health.trim()), (200, "ok: 3 sessions, 6 players"));
    let (status, first) = http_get(&addr, "/metrics");
    assert_eq!(status, 200, "{first}");
    let value = |text: &str, name: &str| sample(text, name).unwrap_or_else(|| panic!("{name} in {text}"));
    assert_eq!(value(&first, "heist_sessions"), 3.0);
    assert_eq!(value(&first, "heist_sessions_created_total"), 3.0);
    assert_eq!(value(&first, "heist_players"), 6.0);
    assert_eq!(value(&first, "heist_draining"), 0.0);
    std::thread::sleep(Duration::from_millis(500));
    let (_, second) = http_get(&addr, "/metrics");
    for name in [
        "heist_tick_seconds_count",
        "heist_tick_cpu_seconds_total",
        "heist_received_bytes_total",
        "heist_sent_bytes_total",
    ] {
        assert!(value(&second, name) > value(&first, name), "{name} grows while the load plays: {second}");
    }
    // The updates' CPU time is at most their wall time (one thread runs them all).
    let cpu = value(&second, "heist_tick_cpu_seconds_total");
    assert!(cpu <= value(&second, "heist_tick_seconds_sum") * 1.05 + 0.01, "{second}");
    assert_eq!(http_get(&addr, "/nothing").0, 404);

    assert!(wait_for(&mut load, Duration::from_secs(120)).is_some_and(|s| s.success()), "the load ends");
    let last: Vec<String> = out.try_iter().collect();
    let report: serde_json::Value = serde_json::from_str(last.last().unwrap()).unwrap();
    assert_eq!((report["sessions"].as_f64(), report["players"].as_f64()), (Some(3.0), Some(6.0)), "{report}");
}

#[test]
fn sigterm_drains_an_agones_served_server_two_heists_finish_new_sessions_are_refused_and_it_exits_0() {
    use agones_fake::{Declared, FakeAgones};
    use std::time::{Duration, Instant};
    let fake = FakeAgones::start(
        "127.0.0.1:0".parse().unwrap(),
        Declared {
            counters: vec![("sessions".into(), 1000)],
            lists: vec![("players".into(), 1000)],
            ports: Vec::new(),
        },
    )
    .unwrap();
    let bin = env!("CARGO_BIN_EXE_heist-server");
    let args =
        ["--max-sessions", "4", "--time-limit", "15", "--drain-limit", "60", "--agones", "--metrics", "127.0.0.1:0"];
    let envs = [("AGONES_SDK_GRPC_PORT", fake.addr.port().to_string())];
    let (mut serve, addr, _, out, log) = serve_on_a_free_port_with("serve", &args, &envs);
    line_after(&out, "serving", Duration::from_secs(20));
    let metrics = line_after(&out, "health and metrics on http://", Duration::from_secs(20));
    let metrics = metrics.split('/').next().unwrap().to_owned();
    assert!(fake.wait_for(Duration::from_secs(20), |r| r.ready == 1), "Ready once serving");

    let cache = std::env::temp_dir().join(format!("heist-cli-seats-{}-drain", std::process::id()));
    let (mut bots, _) = bot_pairs(&addr, &cache, 2);
    // Both heists under way (and Agones counting both sessions), then the game server is allocated.
    let mut events: Vec<serde_json::Value> = Vec::new();
    let mut read_log = |until: &dyn Fn(&[serde_json::Value]) -> bool, limit: Duration| {
        let deadline = Instant::now() + limit;
        while !until(&events) && Instant::now() < deadline {
            if let Ok(line) = log.recv_timeout(Duration::from_millis(100))
                && let Ok(v) = serde_json::from_str::<serde_json::Value>(&line)
            {
                events.push(v);
            }
        }
        until(&events)
    };
    let count = |events: &[serde_json::Value], name: &str| events.iter().filter(|e| e["event"] == name).count();
    let heists = |e: &[serde_json::Value]| e.iter().filter(|e| e["event"] == "phase" && e["phase"] == "heist").count();
    assert!(read_log(&|e| heists(e) == 2, Duration::from_secs(30)), "two heists begin: {events:?}");
    assert!(
        fake.wait_for(Duration::from_secs(10), |r| r.counters["sessions"].0 == 2 && r.lists["players"].1.len() == 4)
    );
    fake.allocate();
    assert!(read_log(&|e| count(e, "allocated") == 1, Duration::from_secs(10)), "the allocation is logged");

    // SIGTERM: no new session, a clear refusal; health says draining.
    // SAFETY: kill(2) on our own child's pid with a valid signal number.
    assert_eq!(unsafe { libc::kill(serve.id() as i32, libc::SIGTERM) }, 0);
    assert!(read_log(&|e| count(e, "drain_started") == 1, Duration::from_secs(10)), "{events:?}");
    let refused = Command::new(bin).args(["join", &addr, "--create", "--role", "vive"]).output().unwrap();
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success() && err.contains("shutting down"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    let (status, health) = http_get(&metrics, "/healthz");
    assert_eq!((status, health.trim()), (503, "draining: 2 sessions left"));

    // Both heists reach their result, the sessions end, the server exits 0 and told Agones Shutdown.
    let status = wait_for(&mut serve, Duration::from_secs(60));
    assert!(status.is_some_and(|s| s.success()), "the drained server exits 0: {status:?}");
    read_log(&|_| false, Duration::from_millis(300));
    assert_eq!(count(&events, "result"), 2, "{events:?}");
    assert_eq!(count(&events, "session_ended"), 2, "{events:?}");
    assert_eq!(count(&events, "drained"), 1, "{events:?}");
    assert!(events.iter().filter(|e| e["event"] == "result").all(|e| e["reason"] == "time"), "played to the end");
    let r = fake.recorded();
    assert_eq!(r.shutdown, 1, "{:?}", r.calls);
    assert!(r.lists["players"].1.is_empty() && r.counters["sessions"].0 == 0, "{:?}", r.calls);
    let mut told = 0;
    for (b, printed) in &mut bots {
        let _ = wait_for(b, Duration::from_secs(10));
        told += usize::from(printed.try_iter().any(|l| l.contains("The server has shut down")));
    }
    assert_eq!(told, 4, "every player is told the server shut down");
    let _ = std::fs::remove_dir_all(cache);
}

/// The lines of `text` from the one that is `header` (trimmed) up to the next line indented as little.
fn yaml_block<'a>(text: &'a str, header: &str) -> Vec<&'a str> {
    let lines: Vec<&str> = text.lines().collect();
    let at = lines.iter().position(|l| l.trim() == header).unwrap_or_else(|| panic!("{header} in the YAML"));
    let indent = |l: &str| l.len() - l.trim_start().len();
    let own = indent(lines[at]);
    lines[at + 1..].iter().take_while(|l| l.trim().is_empty() || indent(l) > own).copied().collect()
}

/// The number after `key:` in `lines`, the first one.
fn yaml_number(lines: &[&str], key: &str) -> f64 {
    lines
        .iter()
        .find_map(|l| l.trim().strip_prefix(key)?.strip_prefix(':')?.trim().trim_matches('"').parse().ok())
        .unwrap_or_else(|| panic!("{key} in {lines:?}"))
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            files.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
    files
}

/// The server container's arguments in deploy/fleet.yaml.
fn fleet_args(fleet: &str) -> Vec<String> {
    yaml_block(fleet, "args:")
        .iter()
        .map_while(|l| l.trim().strip_prefix("- ").map(|a| a.trim_matches('"').to_owned()))
        .collect()
}

fn arg_after(args: &[String], flag: &str) -> f64 {
    let at = args.iter().position(|a| a == flag).unwrap_or_else(|| panic!("{flag} in {args:?}"));
    args[at + 1].parse().unwrap()
}

/// The Dockerfile's build stage installs what `scripts/deps.sh` installs for CI and builds the server in
/// release. CI builds the same code in the test profile (`scripts/test.sh`) and no longer builds it again
/// in release (docs/performance.md): the two profiles compile the same sources the same way as long as
/// none of the server's crates branches on `debug_assertions`, which this test also holds.
#[test]
fn the_dockerfiles_build_stage_runs_what_ci_checks_and_ships_only_the_server_as_a_user() {
    let dockerfile = include_str!("../../deploy/Dockerfile");
    let deps = include_str!("../../scripts/deps.sh");
    let stages: Vec<&str> = dockerfile.split("\nFROM ").skip(1).collect();
    assert_eq!(stages.len(), 2, "two stages: build and runtime");
    let runs: Vec<&str> = stages[0].lines().filter_map(|l| l.strip_prefix("RUN ")).collect();
    assert_eq!(runs, ["bash scripts/server-deps.sh", "cargo build --release --locked -p heist_server"]);
    assert!(
        deps.lines().any(|l| l.trim_start().starts_with("bash ") && l.trim_end().ends_with("/server-deps.sh\"")),
        "scripts/deps.sh, which CI runs, runs server-deps.sh"
    );
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for krate in ["server", "shared/core", "shared/client", "shared/bots", "shared/transport"] {
        for file in rust_files(&root.join(krate).join("src")) {
            let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            assert!(!text.contains("debug_assertions"), "{} branches on debug_assertions", file.display());
        }
    }
    let runtime = stages[1];
    let copies: Vec<&str> = runtime.lines().filter(|l| l.starts_with("COPY")).collect();
    assert_eq!(copies.len(), 2, "the binary and the levels: {copies:?}");
    assert!(copies[0].contains("target/release/heist-server") && copies[1].contains("assets/levels"), "{copies:?}");
    let user = runtime.lines().find_map(|l| l.strip_prefix("USER ")).expect("a USER line");
    assert!(!user.starts_with("root") && !user.starts_with("0"), "runs as {user}");
}

#[test]
fn the_fleet_sizes_agree_with_the_server_it_runs_and_the_levels_it_plays() {
    use heist_server::fleet::agones::{GAME_PORT, PLAYERS_LIST, SESSIONS_COUNTER};
    let fleet = include_str!("../../deploy/fleet.yaml");
    let args = fleet_args(fleet);
    let max = arg_after(&args, "--max-sessions");
    let drain = arg_after(&args, "--drain-limit");
    assert!(args.iter().any(|a| a == "--agones"), "{args:?}");
    let counter = yaml_block(fleet, &format!("{SESSIONS_COUNTER}:"));
    assert_eq!(yaml_number(&counter, "capacity"), max, "the Counter's capacity is --max-sessions");
    let list = yaml_block(fleet, &format!("{PLAYERS_LIST}:"));
    assert_eq!(yaml_number(&list, "capacity"), 2.0 * max, "two seats a session");
    let grace = yaml_number(&fleet.lines().collect::<Vec<_>>(), "terminationGracePeriodSeconds");
    let heist = f64::from(heist_shared::level::Level::museum().time_limit_s);
    assert!(grace > drain && drain > heist, "grace {grace} > drain {drain} > a heist {heist}");
    let health = yaml_block(fleet, "health:");
    let window = yaml_number(&health, "periodSeconds") * yaml_number(&health, "failureThreshold");
    assert!(window > heist_server::fleet::STALL_AFTER.as_secs_f64(), "Agones waits longer than the watchdog");
    let ports = yaml_block(fleet, "ports:");
    assert!(ports.iter().any(|l| l.trim() == format!("- name: {GAME_PORT}")), "{ports:?}");
    let autoscaler = yaml_block(fleet, "counter:");
    assert!(autoscaler.iter().any(|l| l.trim() == format!("key: {SESSIONS_COUNTER}")), "{autoscaler:?}");
    assert_eq!(yaml_number(&autoscaler, "bufferSize") % max, 0.0, "the buffer is whole servers");
}

#[test]
fn the_fleets_arguments_run_a_server_on_the_passthrough_port_and_a_second_sigterm_exits_at_once() {
    use agones_fake::{Declared, FakeAgones};
    use std::process::Stdio;
    use std::time::Duration;
    let fleet = include_str!("../../deploy/fleet.yaml");
    let fleet_args = fleet_args(fleet);
    let shards = (arg_after(&fleet_args, "--max-sessions") / arg_after(&fleet_args, "--shard-size")).ceil() as usize;
    let free: Vec<u16> =
        (0..shards).map(|_| std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()).collect();
    let port = free[0];
    // As Agones' port allocator lists a TCPUDP port (`game`), then the shards' UDP ports.
    let mut ports = vec![("game-tcp".to_owned(), port), ("game-udp".to_owned(), port)];
    ports.extend(free.iter().enumerate().skip(1).map(|(i, p)| (heist_server::fleet::agones::game_port_name(i), *p)));
    let declared_ports = yaml_block(fleet, "ports:");
    for (name, _) in ports.iter().skip(2) {
        assert!(declared_ports.iter().any(|l| l.trim() == format!("- name: {name}")), "the fleet declares {name}");
    }
    let fake = FakeAgones::start(
        "127.0.0.1:0".parse().unwrap(),
        Declared { counters: vec![("sessions".into(), 32)], lists: vec![("players".into(), 64)], ports },
    )
    .unwrap();
    // The container's arguments, on loopback (tests bind nothing else) with a free metrics port.
    let args: Vec<String> = fleet_args
        .into_iter()
        .map(|a| if a.starts_with("0.0.0.0:") { a.replace("0.0.0.0", "127.0.0.1") } else { a })
        .map(|a| if a == "127.0.0.1:9090" { "127.0.0.1:0".to_owned() } else { a })
        .collect();
    let bin = env!("CARGO_BIN_EXE_heist-server");
    let mut serve = Command::new(bin)
        .args(["--log-format", "json", "serve"])
        .args(&args)
        .env("AGONES_SDK_GRPC_PORT", fake.addr.port().to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = lines_of(serve.stdout.take().unwrap());
    let log = lines_of(serve.stderr.take().unwrap());
    let hosting = line_after(&out, "hosting on ", Duration::from_secs(40));
    assert_eq!(hosting, format!("127.0.0.1:{port} (UDP game, TCP tokens)"), "the Passthrough port, Agones' address");
    // The server says Ready, then sets its annotation: wait for both (on a busy machine the second
    // can land after a check made right after the first).
    let announced = |r: &agones_fake::Recorded| r.ready == 1 && r.annotations.contains_key("phantom-heist.address");
    assert!(fake.wait_for(Duration::from_secs(10), announced));
    assert_eq!(fake.recorded().annotations.get("phantom-heist.address"), Some(&format!("127.0.0.1:{port}")));

    // A heist under way; SIGTERM starts a drain, a second SIGTERM exits at once with 128 + 15.
    let addr = format!("127.0.0.1:{port}");
    let cache = std::env::temp_dir().join(format!("heist-cli-seats-{}-fleet", std::process::id()));
    let (mut bots, _) = bot_pairs(&addr, &cache, 1);
    line_after(&log, r#""phase":"heist""#, Duration::from_secs(30));
    // SAFETY: kill(2) on our own child's pid with a valid signal number.
    assert_eq!(unsafe { libc::kill(serve.id() as i32, libc::SIGTERM) }, 0);
    line_after(&log, "drain_started", Duration::from_secs(10));
    assert!(serve.try_wait().unwrap().is_none(), "the first SIGTERM waits for the heist");
    // SAFETY: as above.
    assert_eq!(unsafe { libc::kill(serve.id() as i32, libc::SIGTERM) }, 0);
    let status = wait_for(&mut serve, Duration::from_secs(5));
    assert_eq!(status.and_then(|s| s.code()), Some(143), "the second SIGTERM exits at once");
    for (b, _) in &mut bots {
        let _ = b.kill();
        let _ = b.wait();
    }
    let _ = std::fs::remove_dir_all(cache);
}
