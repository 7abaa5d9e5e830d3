//! haptic-bench's surface renderings: the gemstone's shell, and both surfaces, on the scripted path.

use std::process::Command;

fn haptic_bench(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_haptic-bench"))
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("haptic-bench runs")
}

#[test]
fn haptic_bench_renders_the_path_with_both_surfaces_and_says_so() {
    let out = haptic_bench(&[
        "--lockstep",
        "--seconds",
        "12",
        "--bunny-spheres",
        "1500",
        "--tool-spheres",
        "150",
        "--surface",
        "--shell-edge-mm",
        "1",
        "--both-surfaces",
        "--json",
    ]);
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stderr.contains("the gemstone's shell of") && stderr.contains("the bunny's of"), "{stderr}");
    let json: serde_json::Value = serde_json::from_str(stdout.lines().last().unwrap_or_default()).expect("JSON");
    assert_eq!((json["both_surfaces"].as_bool(), json["shell_edge_mm"].as_f64()), (Some(true), Some(1.0)), "{json}");
    let (ticks, forced) = (json["ticks"].as_u64(), json["ticks_with_force"].as_u64().unwrap_or(0));
    assert!(ticks == Some(12_000) && forced > 10_000 && json["max_force_n"].as_f64() > Some(0.1), "{json}");
}

#[test]
fn haptic_bench_refuses_a_surface_option_without_what_it_needs_on_one_line() {
    for (args, says) in [
        (&["--both-surfaces"][..], "--both-surfaces needs --shell-edge-mm"),
        (&["--shell-edge-mm", "0.5"][..], "needs --surface"),
        (&["--surface", "--shell-edge-mm", "0.01"][..], "takes 0.2 to 10"),
    ] {
        let out = haptic_bench(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && stderr.lines().count() == 1, "{args:?}: {stderr}");
        assert!(stderr.starts_with("error:") && stderr.contains(says), "{args:?}: {stderr}");
    }
}
