#!/usr/bin/env bash
# Installs the system packages the workspace needs to build and test (Debian/Ubuntu).
# Safe to run repeatedly: it only calls apt-get when something is missing.
set -euo pipefail
bash "$(dirname "$0")/server-deps.sh"
# Clients: espeak-ng (speech), ALSA headers (sound card, microphone), libopus (the walkie-talkie's codec),
# X/Vulkan runtime + Xvfb (windows and their tests), the OpenXR loader (the Vive client probes it; its
# tests check the fallback without a runtime), OpenSSL headers (the haply crate's HTTP client, reqwest with
# native TLS). What the server alone needs is in server-deps.sh.
packages=(pkg-config libudev-dev libfontconfig1-dev libfreetype-dev fonts-dejavu-core
    espeak-ng libasound2-dev libopus-dev libxkbcommon-x11-0 libvulkan1 mesa-vulkan-drivers xvfb xauth
    libopenxr-loader1 libopenxr-dev libssl-dev)
bash "$(dirname "$0")/apt-install.sh" "${packages[@]}"
