#!/usr/bin/env bash
# Runs a whole heist, headless, with both bots over loopback UDP, and prints the log and the result.
# Extra arguments go to `heist-server demo` (e.g. --seed 4, --vive reckless).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cargo run --release --locked -p heist_server --features bots -- demo "$@"
