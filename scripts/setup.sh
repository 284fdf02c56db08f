#!/usr/bin/env bash
# Installs what skytune needs from Debian on a fresh machine: Vulkan loader, Mesa's lavapipe
# (software Vulkan, used headless and in CI), Xvfb and the X11 libraries winit loads at run time,
# and a C++ compiler for the FLIP image-difference library (nv-flip builds it from source).
# Idempotent: does nothing when everything is present.
set -euo pipefail

packages=(g++ mesa-vulkan-drivers libvulkan1 xvfb xauth libxkbcommon-x11-0 libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon0)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: installing ${missing[*]}"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
command -v cargo >/dev/null || { echo "setup: cargo not found; install Rust (rustup) first" >&2; exit 1; }
echo "setup: system packages ready"
