#!/usr/bin/env bash
# Runs every test of the workspace (installs the system packages it needs first), after the checks CI
# holds every change to: formatting and clippy with warnings as errors.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cargo fmt --all --check
cargo clippy --workspace --all-targets --locked -- -D warnings
cargo test --workspace --locked "$@"
