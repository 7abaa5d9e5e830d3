//! The terminal a blind player lives in: with `--headless`, stdout carries each spoken line once and
//! nothing else (no `SAY:` tags, no log lines, no telemetry), and the log on stderr stays quiet unless
//! `RUST_LOG` asks for more. Played as a screen-reader user would: answering by typed lines.

use std::io::{Read, Write};
use std::process::Command;
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::{Duration, Instant};

mod common;
use common::{headless, headless_with_cache, hear, host_with_a_vive_bot, wait};

#[test]
fn headless_practice_prints_each_spoken_line_once_and_nothing_else_and_records_the_device() {
    let trace = std::env::temp_dir().join(format!("phantom-practice-{}.trace", std::process::id()));
    let trace_arg = trace.to_str().expect("utf-8 path");
    let (mut child, mut stdin, rx) = headless(&["practice", "--kind", "crown", "--seed", "3", "--record", trace_arg]);
    let mut stderr = child.stderr.take().expect("stderr");
    let log = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    // Three copies, answered real, fake, real as each can be felt; a word that is no key first.
    let (mut answers, mut lines) = (["y", "n", "y"].into_iter(), Vec::new());
    let deadline = Instant::now() + Duration::from_secs(240);
    loop {
        match rx.recv_timeout(Duration::from_millis(200)) {
            Ok(line) => {
                if line.starts_with("You can feel it now") {
                    if lines.iter().all(|l: &String| !l.starts_with("You can feel it now")) {
                        writeln!(stdin, "xyzzy").expect("types");
                    }
                    writeln!(stdin, "{}", answers.next().unwrap_or("y")).expect("types");
                }
                lines.push(line);
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => break,
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("the practice did not end within 4 minutes; it printed {lines:#?}");
        }
    }
    let status = child.wait().expect("waits");
    let log = log.join().expect("the log");
    assert!(status.success(), "client_haptic exited with {status}; stderr: {log}");

    let count = |prefix: &str| lines.iter().filter(|l| l.starts_with(prefix)).count();
    assert_eq!(count("Welcome to Phantom Heist."), 1, "{lines:#?}");
    assert_eq!(count("A copy of the crown is on the bench."), 3, "{lines:#?}");
    assert_eq!(count("You can feel it now."), 3, "{lines:#?}");
    assert_eq!(count("You say: "), 3, "{lines:#?}");
    assert_eq!(
        count("Type y, n, s, b, r, h, g, c, o, q, talk, over, up, down, left, right, or just Enter."),
        1,
        "the word that is no key: {lines:#?}"
    );
    // In the order a player needs them: the welcome first, each verdict's answer before the next copy.
    let at = |prefix: &str| -> Vec<usize> {
        lines.iter().enumerate().filter(|(_, l)| l.starts_with(prefix)).map(|(i, _)| i).collect()
    };
    let copies = at("A copy of the crown is on the bench.");
    let answers = [at("Correct."), at("Wrong:")].concat();
    assert!(at("Welcome").iter().all(|w| *w < copies[0]), "{lines:#?}");
    assert_eq!(answers.len(), 3, "{lines:#?}");
    for next in &copies[1..] {
        assert_eq!(
            answers.iter().filter(|a| *a < next).count(),
            copies.iter().filter(|c| *c < next).count(),
            "{lines:#?}"
        );
    }
    let last = lines.last().expect("something was said");
    assert!(last.starts_with("Practice over: ") && last.ends_with(" wrong."), "said last: {lines:#?}");
    for line in &lines {
        let sentence = line.ends_with(['.', '!', '?']) && line.chars().next().is_some_and(char::is_uppercase);
        assert!(sentence && !line.starts_with("SAY:") && !line.contains('\u{1b}'), "not a spoken line: {line:?}");
    }
    for noise in ["INFO", "DEBUG", "haptic loop", "SAY", "said:", "\u{1b}["] {
        assert!(!log.contains(noise), "the log is quiet by default, yet has {noise:?}: {log}");
    }
    // `--record`: the device's every tick of the practice, in the documented format, to its end.
    let recorded = haptico::trace::load_trace(&trace).expect("the trace reads back");
    let states = &recorded.states;
    let span_s = (states.last().expect("ticks").timestamp_us - states[0].timestamp_us) as f64 * 1e-6;
    assert!(span_s > 3.0 && states.len() as f64 > 0.8 * 1000.0 * span_s, "{} ticks over {span_s:.1} s", states.len());
    assert_eq!(recorded.commands.map(|c| c.len()), Some(states.len()));
    std::fs::remove_file(&trace).ok();
}

#[test]
fn a_join_that_cannot_reach_the_host_fails_on_one_line_without_a_backtrace() {
    // Nothing listens on port 1; RUST_BACKTRACE as a developer's shell has it.
    let out = Command::new(env!("CARGO_BIN_EXE_client_haptic"))
        .args(["join", "127.0.0.1:1", "--code", "ABCD-EFGH-JKLM", "--headless", "--audio", "memory"])
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("client_haptic runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "one line: {err}");
    assert!(lines[0].starts_with("error: joining 127.0.0.1:1 as Phantom: cannot reach the token endpoint"), "{err}");
    assert_eq!(lines[0].matches("refused").count(), 1, "the cause once: {err}");
}

#[test]
fn a_blind_player_hears_the_partner_plays_a_rematch_and_leaves_by_typed_lines() {
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let (addr, code, host) = host_with_a_vive_bot(stop.clone(), Default::default(), 4.0);
    let (mut child, mut stdin, rx) = headless(&["join", &addr.to_string(), "--code", &code]);
    // Ready when the partner is in; after the first result, Enter for another round; after the second, q.
    let mut lines: Vec<String> = Vec::new();
    let mut results = 0;
    let deadline = Instant::now() + Duration::from_secs(90);
    loop {
        match rx.recv_timeout(Duration::from_millis(200)) {
            Ok(line) => {
                if line == "Vive joined." {
                    writeln!(stdin).expect("types Enter: ready");
                }
                if line.starts_with("Enter asks for another round") {
                    results += 1;
                    writeln!(stdin, "{}", if results == 1 { "again" } else { "q" }).expect("types");
                }
                lines.push(line);
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => break,
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
            panic!("the two rounds did not end within 90 s; Phantom heard {lines:#?}");
        }
    }
    let status = child.wait().expect("waits");
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let log = host.join().expect("the host thread");
    assert!(status.success(), "client_haptic exited with {status}");
    println!("Phantom heard:\n{}", lines.join("\n"));
    let at = |text: &str| {
        lines.iter().position(|l| l.starts_with(text)).unwrap_or_else(|| panic!("{text:?} was never said: {lines:#?}"))
    };
    let order = [
        at("Vive joined."),
        at("The heist has begun."),
        at("Time is up. The heist is lost."),
        at("Round 2 begins"),
        at("Leaving the session."),
    ];
    assert!(order.windows(2).all(|w| w[0] < w[1]), "said out of order: {lines:#?}");
    assert!(lines.iter().any(|l| l == "Vive asks for another round." || l.starts_with("You asked for another round")));
    assert_eq!(lines.iter().filter(|l| l.starts_with("The heist has begun.")).count(), 2, "{lines:#?}");
    assert_eq!(lines.iter().filter(|l| l.starts_with("Time is up.")).count(), 2, "{lines:#?}");
    assert!(log.iter().any(|l| l.ends_with("round 2 begins")), "{log:#?}");
    assert!(log.iter().any(|l| l.ends_with("Phantom left")), "a clean leave, not a drop: {log:#?}");
}

#[test]
fn a_blind_player_hosts_alone_hears_the_code_spelled_and_a_partner_joins_with_it() {
    let port = std::net::UdpSocket::bind("127.0.0.1:0").expect("a free port").local_addr().expect("addr").port();
    let bind = format!("127.0.0.1:{port}");
    host_and_hear_a_partner_join(&["host", "--bind", &bind], &bind);
}

#[test]
fn a_blind_player_creates_a_session_on_a_running_server_and_a_partner_joins_with_its_code() {
    use std::sync::atomic::{AtomicBool, Ordering};
    let stop = std::sync::Arc::new(AtomicBool::new(false));
    let (tx, rx) = mpsc::channel();
    let serving = stop.clone();
    // `heist-server serve`, in-process: no session until a player creates one.
    let server = std::thread::spawn(move || {
        let mut options = heist_server::ServerOptions::local_test(0);
        options.host_session = false;
        options.max_sessions = 4;
        let mut server = heist_server::build_server(options).expect("server starts");
        tx.send(server.tokens.as_ref().expect("secure").addr).expect("the test waits");
        let deadline = Instant::now() + Duration::from_secs(90);
        while !serving.load(Ordering::Relaxed) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(16));
            server.update();
        }
        server.sessions().len()
    });
    let addr = rx.recv_timeout(Duration::from_secs(30)).expect("the server starts").to_string();
    host_and_hear_a_partner_join(&["host", "--server", &addr], &addr);
    stop.store(true, Ordering::Relaxed);
    assert_eq!(server.join().expect("the server thread"), 1, "the session was created on the running server");
}

/// Runs `client_haptic <args>` (a host), joins a Vive bot with the code it says, leaves once Vive is in,
/// and checks what was said; `addr` is where the partner was told to join.
fn host_and_hear_a_partner_join(args: &[&str], addr: &str) {
    use heist_shared::protocol::{Role, TICK_HZ};
    let (mut child, mut stdin, rx) = headless(args);
    let mut lines: Vec<String> = Vec::new();
    let mut vive: Option<bevy::app::App> = None;
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut done = false;
    while !done {
        assert!(Instant::now() < deadline, "no partner joined within 60 s; Phantom heard {lines:#?}");
        while let Ok(line) = rx.try_recv() {
            // The code as a sighted or screen-reader user reads it off the line, and a partner joins with it.
            if let Some(code) = line.split("with the code ").nth(1).map(|c| c.trim_end_matches('.').to_owned()) {
                let token =
                    heist_client::request_token(addr.parse().expect("addr"), &code, Role::Vive, Duration::from_secs(5))
                        .expect("the spoken code admits the partner");
                let mut app = heist_server::demo::stepped_client_app();
                app.add_plugins(heist_bots::ViveBotPlugin { style: heist_bots::ViveStyle::Idle });
                app.finish();
                app.cleanup();
                heist_client::connect(&mut app, token).expect("connects");
                vive = Some(app);
            }
            if line == "Vive joined." {
                writeln!(stdin, "q").expect("types q: leave");
            }
            if line == "Leaving the session." {
                done = true;
            }
            lines.push(line);
        }
        if let Some(v) = vive.as_mut() {
            v.update();
        }
        std::thread::sleep(Duration::from_secs_f64(1.0 / TICK_HZ));
    }
    let status = child.wait().expect("waits");
    assert!(status.success(), "client_haptic exited with {status}: {lines:#?}");
    let hosted = lines.iter().find(|l| l.starts_with("You host the heist.")).expect("the host line");
    let code = hosted.split("with the code ").nth(1).expect("a code").trim_end_matches('.');
    let spelled = format!("The code, spelled: {}. R repeats it.", client_haptic::prompt::spell(code));
    let at = |l: &str| lines.iter().position(|x| x == l);
    let welcome = lines.iter().position(|l| l.starts_with("Welcome")).expect("welcomed");
    assert!(at(&spelled).is_some_and(|s| s > welcome), "the spelled code comes last, for R: {lines:#?}");
    assert!(hosted.contains(addr), "the address to join is said: {hosted}");
    assert!(!lines.iter().any(|l| l.contains("server is gone")), "leaving on purpose is no lost server: {lines:#?}");
}

#[test]
fn a_blind_player_hears_the_link_lost_gets_back_in_by_itself_and_after_a_restart() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let (stop, stall) = (Arc::new(AtomicBool::new(false)), Arc::new(AtomicBool::new(false)));
    let (addr, code, host) = host_with_a_vive_bot(stop.clone(), stall.clone(), 300.0);
    let cache = std::env::temp_dir().join(format!("phantom-terminal-{}-rejoin", std::process::id()));
    let join = ["join", &addr.to_string(), "--code", &code].map(str::to_owned);
    let join: Vec<&str> = join.iter().map(String::as_str).collect();
    let (mut child, mut stdin, rx) = headless_with_cache(&join, &cache);
    let mut lines = Vec::new();
    let t = Duration::from_secs(30);
    assert!(hear(&rx, &mut lines, "Vive joined.", t), "{lines:#?}");
    writeln!(stdin).expect("types Enter: ready");
    assert!(hear(&rx, &mut lines, "The heist has begun.", t), "{lines:#?}");

    // The server's loop stalls: within seconds Phantom hears it and the client tries to get back in.
    stall.store(true, Ordering::Relaxed);
    assert!(hear(&rx, &mut lines, "The connection to the server is lost.", Duration::from_secs(6)), "{lines:#?}");
    assert!(hear(&rx, &mut lines, "Trying to get back into the session.", Duration::from_secs(3)), "{lines:#?}");
    std::thread::sleep(Duration::from_secs(2));
    stall.store(false, Ordering::Relaxed);
    assert!(hear(&rx, &mut lines, "You are back in your seat.", t), "{lines:#?}");

    // The client is killed; started again, it takes the seat back with the ticket in its seat cache.
    child.kill().expect("kills");
    let _ = child.wait();
    let (mut again, mut stdin, rx) = headless_with_cache(&join, &cache);
    let restarted = lines.len();
    assert!(hear(&rx, &mut lines, "You are back in your seat.", t), "{lines:#?}");
    let told_where = lines[restarted..].iter().any(|l| l.starts_with("The heist is on."))
        || hear(&rx, &mut lines, "The heist is on.", t);
    assert!(told_where, "where the heist stands, not the lobby's menu: {lines:#?}");
    assert!(!lines[restarted..].iter().any(|l| l.starts_with("Ready.")), "{lines:#?}");
    writeln!(stdin, "q").expect("types q: leave");
    assert!(hear(&rx, &mut lines, "Leaving the session.", t), "{lines:#?}");
    let status = wait(&mut again, Duration::from_secs(10));
    stop.store(true, Ordering::Relaxed);
    let log = host.join().expect("the host thread");
    println!("Phantom heard:\n{}", lines.join("\n"));
    assert!(status.is_some_and(|s| s.success()), "client_haptic exited with {status:?}: {lines:#?}");
    assert_eq!(log.iter().filter(|l| l.contains("Phantom is back")).count(), 2, "{log:#?}");
    assert!(!lines.iter().any(|l| l.starts_with("Could not get back")), "{lines:#?}");
    let _ = std::fs::remove_dir_all(cache);
}
