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
