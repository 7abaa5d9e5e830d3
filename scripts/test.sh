#!/usr/bin/env bash
# Runs every test of the workspace (installs the system packages it needs first), after the checks CI
# holds every change to: formatting, and clippy with warnings as errors.
#
# Clippy lints the workspace's crates while they are built for the tests (clippy-driver as cargo's
# workspace wrapper, as `cargo clippy` itself sets it; `--all-targets`: libraries, binaries, tests,
# examples and benches), instead of a separate `cargo clippy` that would check every dependency a second
# time: the same lints, about 12 minutes less on a fresh clone (docs/performance.md, "The test suite's
# own time"). Arguments go to the test run (e.g. `-p heist_server`, a test's name).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cargo fmt --all --check
# The haptics libraries stay publishable (docs/bevy-haptics.md): packaged without a verify build (the
# registry cannot resolve our own unpublished crates), and bevy_haptics links none of the tools' crates.
cargo package --locked --no-verify --quiet \
    -p haptic_common -p haptico -p collette_ist -p forcecomp -p haptic_rig -p bevy_haptics
if cargo tree --locked -p bevy_haptics -e normal --prefix none | grep -E '^(clap|indicatif|plotters|png) v'; then
    echo "bevy_haptics links a command-line tool's crate (above): keep it behind a feature" >&2
    exit 1
fi
RUSTC_WORKSPACE_WRAPPER="$(rustup which clippy-driver 2>/dev/null || command -v clippy-driver)" || {
    echo "clippy-driver not found: install clippy (rustup component add clippy)" >&2
    exit 1
}
export RUSTC_WORKSPACE_WRAPPER
# What `cargo clippy -- -D warnings` hands the driver (each argument followed by the separator it splits on).
export CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__"
cargo test --workspace --all-targets --locked --no-run
cargo test --workspace --locked "$@"
