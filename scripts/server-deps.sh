#!/usr/bin/env bash
# Installs the system packages the server alone needs to build (Debian/Ubuntu): protoc, for the Agones
# SDK's gRPC code (the agones crate compiles its .proto files at build time). Used by deps.sh (CI, the
# demo) and by the server's container image (deploy/Dockerfile). Only calls apt-get when something is missing.
set -euo pipefail
packages=(protobuf-compiler)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "installing system packages: ${missing[*]}"
    sudo_cmd=""
    [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
    $sudo_cmd apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${missing[@]}"
fi
