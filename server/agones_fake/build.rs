//! Generates the server side of Agones' SDK from the `.proto` files the `agones` crate ships (it builds
//! only the client side from them). The crate's sources are found through `cargo metadata`, so the
//! protocol is always the one of the `agones` version in Cargo.lock. The metadata is filtered to the
//! platform being built for: offline, cargo has only that platform's crates (a dependency's macOS-only
//! crates, say, were never downloaded on Linux).

use std::path::PathBuf;
use std::process::Command;

fn agones_dir() -> Result<PathBuf, String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").map_err(|e| e.to_string())?).join("Cargo.toml");
    let target = std::env::var("TARGET").map_err(|e| format!("cargo set no TARGET: {e}"))?;
    let out = Command::new(cargo)
        .args(["metadata", "--format-version", "1", "--locked", "--offline", "--filter-platform", &target])
        .arg("--manifest-path")
        .arg(&manifest)
        .output()
        .map_err(|e| format!("cannot run cargo metadata: {e}"))?;
    if !out.status.success() {
        return Err(format!("cargo metadata failed: {}", String::from_utf8_lossy(&out.stderr)));
    }
    let meta: serde_json::Value =
        serde_json::from_slice(&out.stdout).map_err(|e| format!("cargo metadata printed no JSON: {e}"))?;
    let packages = meta["packages"].as_array().ok_or("cargo metadata lists no packages")?;
    let agones =
        packages.iter().find(|p| p["name"] == "agones").ok_or("the agones crate is not in the dependency graph")?;
    let path = PathBuf::from(agones["manifest_path"].as_str().ok_or("agones has no manifest path")?);
    path.parent().map(PathBuf::from).ok_or_else(|| "agones' manifest has no folder".into())
}

fn main() {
    let dir = agones_dir().unwrap_or_else(|e| panic!("cannot find the agones crate's .proto files: {e}"));
    let proto = dir.join("proto");
    let includes = ["googleapis", "grpc-gateway", "sdk/alpha", "sdk/beta", "sdk"].map(|d| proto.join(d));
    tonic_build::configure()
        .build_client(false)
        .build_server(true)
        .compile_protos(&[proto.join("sdk/sdk.proto"), proto.join("sdk/beta/beta.proto")], &includes)
        .unwrap_or_else(|e| panic!("cannot compile Agones' SDK protocol from {}: {e}", proto.display()));
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed={}", proto.display());
}
