//! The `client_vr` command's errors: one line that says what failed, never a backtrace.

use std::process::Command;

#[test]
fn a_join_that_cannot_reach_the_host_fails_on_one_line_without_a_backtrace() {
    // Nothing listens on port 1; RUST_BACKTRACE as a developer's shell has it.
    let out = Command::new(env!("CARGO_BIN_EXE_client_vr"))
        .args(["join", "127.0.0.1:1", "--code", "ABCD-EFGH-JKLM", "--headless", "--bot"])
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("client_vr runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(!err.contains("backtrace") && !err.contains("panicked"), "{err}");
    let last = err.trim().lines().last().unwrap_or_default();
    assert!(last.starts_with("error: joining 127.0.0.1:1 as Vive: cannot reach the token endpoint"), "{err}");
    assert_eq!(last.matches("refused").count(), 1, "the cause once: {err}");
}

#[test]
fn vive_hosts_prints_the_code_and_phantom_joins_with_it_and_they_play_a_heist() {
    use std::io::{BufRead, BufReader};
    use std::time::{Duration, Instant};
    let port = std::net::UdpSocket::bind("127.0.0.1:0").expect("a free port").local_addr().expect("addr").port();
    let bind = format!("127.0.0.1:{port}");
    let mut child = Command::new(env!("CARGO_BIN_EXE_client_vr"))
        .args(["host", "--bind", &bind, "--time-limit", "4", "--headless", "--bot", "--quit-after", "1"])
        .env_remove("RUST_LOG")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("client_vr runs");
    let mut stdout = BufReader::new(child.stdout.take().expect("stdout"));
    let mut line = String::new();
    stdout.read_line(&mut line).expect("the host line");
    let code = line.trim().strip_prefix(&format!("You host the heist. Phantom joins at {bind} with the code "));
    let code = code.and_then(|c| c.strip_suffix('.')).unwrap_or_else(|| panic!("the code on one line: {line:?}"));
    // Phantom (the bot on the client core) joins with the printed code and readies up.
    let token = heist_client::request_token(
        bind.parse().expect("addr"),
        code,
        heist_shared::protocol::Role::Phantom,
        Duration::from_secs(5),
    )
    .expect("the printed code admits Phantom");
    let mut phantom = heist_server::demo::client_with_token(token, |app| {
        app.add_plugins(heist_bots::PhantomBotPlugin::default());
    })
    .expect("Phantom joins");
    let deadline = Instant::now() + Duration::from_secs(60);
    let status = loop {
        phantom.update();
        std::thread::sleep(Duration::from_millis(16));
        if let Ok(Some(status)) = child.try_wait() {
            break status;
        }
        assert!(Instant::now() < deadline, "the hosted heist did not end within 60 s");
    };
    assert!(status.success(), "client_vr host exited with {status}");
    // The heist ran its four seconds (the idle-careful bot is not caught that fast) and ended on time.
    use heist_shared::protocol::{LossReason, Phase, SessionView};
    let world = phantom.world_mut();
    let phase = world.query::<&SessionView>().iter(world).next().map(|s| s.phase);
    assert_eq!(phase, Some(Phase::Lost(LossReason::Time)), "Phantom saw the hosted heist to its end");
}
