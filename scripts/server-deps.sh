#!/usr/bin/env bash
# Installs the system packages the server alone needs to build (Debian/Ubuntu): protoc, for the Agones
# SDK's gRPC code (the agones crate compiles its .proto files at build time). Used by deps.sh (CI, the
# demo) and by the server's container image (deploy/Dockerfile).
set -euo pipefail
bash "$(dirname "$0")/apt-install.sh" protobuf-compiler
