//! XR start-up without a runtime falls back to the desktop, in both cases a player meets: no OpenXR
//! loader installed at all, and Debian's loader (`libopenxr-loader1`) with no runtime. The probe is the
//! one `client_vr join` runs before opening a window; `xr-check` prints its line.

use std::path::{Path, PathBuf};
use std::process::Command;

use client_vr::xr::{XrProbe, probe};

/// Debian's loader library (scripts/deps.sh installs it).
fn debian_loader() -> PathBuf {
    let candidates = [
        "/usr/lib/x86_64-linux-gnu/libopenxr_loader.so.1",
        "/usr/lib/aarch64-linux-gnu/libopenxr_loader.so.1",
        "/usr/lib/libopenxr_loader.so.1",
    ];
    candidates
        .iter()
        .map(PathBuf::from)
        .find(|p| p.exists())
        .expect("Debian's OpenXR loader is installed (libopenxr-loader1, see scripts/deps.sh)")
}

fn xr_check(loader: Option<&Path>) -> String {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_client_vr"));
    cmd.arg("xr-check").env_remove("XR_RUNTIME_JSON");
    match loader {
        Some(p) => cmd.env(client_vr::xr::probe::LOADER_ENV, p),
        None => cmd.env_remove(client_vr::xr::probe::LOADER_ENV),
    };
    let out = cmd.output().expect("client_vr runs");
    assert!(out.status.success(), "xr-check failed: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).trim().to_owned()
}

#[test]
fn no_loader_installed_means_desktop_mode_with_the_reason() {
    let missing = Path::new("/nonexistent/libopenxr_loader.so.1");
    let p = probe(Some(missing));
    assert!(matches!(p, XrProbe::NoLoader { .. }), "{p:?}");
    let line = xr_check(Some(missing));
    println!("{line}");
    assert!(line.starts_with("desktop mode: no OpenXR loader installed"), "{line}");
}

#[test]
fn debians_loader_without_a_runtime_means_desktop_mode_with_the_reason() {
    let loader = debian_loader();
    let p = probe(Some(&loader));
    match &p {
        XrProbe::NoRuntime { reason } => {
            assert!(reason.contains("RUNTIME_UNAVAILABLE") || reason.contains("RUNTIME_FAILURE"), "{reason}")
        }
        other => panic!("expected no runtime, got {other:?}"),
    }
    let line = xr_check(Some(&loader));
    println!("{line}");
    assert!(line.starts_with("desktop mode: OpenXR loader found but no OpenXR runtime"), "{line}");
    // The system's own lookup (the unversioned name from libopenxr-dev) finds the same loader.
    let line = xr_check(None);
    assert!(line.starts_with("desktop mode: OpenXR loader found but no OpenXR runtime"), "{line}");
}
