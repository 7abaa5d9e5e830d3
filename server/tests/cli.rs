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
