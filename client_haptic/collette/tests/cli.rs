//! End-to-end: the `collette` binary builds, describes and renders a tree, and refuses bad input.

use std::path::PathBuf;
use std::process::Command;

/// The binary, with backtraces asked for (as a developer's shell may): errors still take one line.
fn bin() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_collette"));
    cmd.env("RUST_BACKTRACE", "1");
    cmd
}

fn temp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("collette-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

const CUBE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
f 1 3 2\nf 2 3 4\nf 5 6 7\nf 6 8 7\nf 1 2 5\nf 2 6 5\nf 3 7 4\nf 4 7 8\nf 1 5 3\nf 3 5 7\nf 2 4 6\nf 4 8 6\n";

#[test]
fn build_info_and_render_work_end_to_end() {
    let dir = temp_dir();
    let (obj, ist, png) = (dir.join("cube.obj"), dir.join("cube.ist"), dir.join("cube.png"));
    std::fs::write(&obj, CUBE_OBJ).expect("write obj");
    let out = bin()
        .args(["build"])
        .arg(&obj)
        .arg("-o")
        .arg(&ist)
        .args(["--spheres", "200", "--json"])
        .output()
        .expect("runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json summary");
    assert_eq!(summary["spheres"], 200);
    assert!((summary["mesh_volume"].as_f64().expect("number") - 1.0).abs() < 1e-6);
    assert!(summary["coverage"].as_f64().expect("number") > 0.5);
    assert!(summary["build_seconds"].as_f64().is_some());

    let out = bin().arg("info").arg(&ist).arg("--json").output().expect("runs");
    assert!(out.status.success());
    let info: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json info");
    assert_eq!(info["spheres"], 200);
    let share = info["mesh_share"].as_f64().expect("number");
    assert!((share - 1.0).abs() < 1e-3, "the weighted spheres stand for the whole cube: {share}");
    assert!(info["min_weight"].as_f64().expect("number") >= 1.0);

    let out = bin().arg("render").arg(&ist).arg("-o").arg(&png).args(["--size", "64"]).output().expect("runs");
    assert!(out.status.success());
    assert!(std::fs::read(&png).expect("png written").starts_with(b"\x89PNG"));

    // The spheres reach past the surface by default; `--surface-offset 0` keeps them inside, and an
    // offset out of range is refused on one line.
    let packed = |offset: &str| -> f64 {
        let args = ["--spheres", "200", "--json", "--surface-offset", offset];
        let out = bin().arg("build").arg(&obj).arg("-o").arg(&ist).args(args).output().expect("runs");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let summary: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json summary");
        summary["packed_volume"].as_f64().expect("number")
    };
    let (inside, default) = (packed("0"), summary["packed_volume"].as_f64().expect("number"));
    assert!(inside < 1.0 && default > inside * 1.01, "offset packing {default} against {inside} inside");
    let out = bin().arg("build").arg(&obj).arg("-o").arg(&ist).args(["--surface-offset", "5"]).output().expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("surface offset"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "one line, no backtrace: {err}");

    // A foreign file and an open mesh are clear errors, not panics.
    let out = bin().arg("info").arg(&obj).output().expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("not an .ist file"), "{err}");
    assert!(err.trim().lines().count() == 1 && err.starts_with("error: "), "one line, no backtrace: {err}");
    let open: String = CUBE_OBJ.lines().take(19).map(|l| format!("{l}\n")).collect();
    std::fs::write(&obj, open).expect("write obj");
    let out = bin().arg("build").arg(&obj).arg("-o").arg(&ist).output().expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("edge") && !err.contains("panicked"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "one line, no backtrace: {err}");
    std::fs::remove_dir_all(&dir).ok();
}
