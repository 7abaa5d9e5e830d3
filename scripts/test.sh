#!/usr/bin/env bash
# Runs every test of the workspace (installs the system packages it needs first).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cargo test --workspace --locked "$@"
