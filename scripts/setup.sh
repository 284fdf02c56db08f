#!/usr/bin/env bash
# Installs what skytune needs from Debian on a fresh machine: Vulkan loader, Mesa's lavapipe
# (software Vulkan, used headless and in CI), Xvfb, xwd (x11-apps: the window tests read the
# screen back through it) and the X11 libraries winit loads at run time,
# and a C++ compiler for the FLIP image-difference library (nv-flip builds it from source).
# Idempotent: does nothing when everything is present.
set -euo pipefail

packages=(g++ mesa-vulkan-drivers libvulkan1 xvfb xauth x11-apps libxkbcommon-x11-0 libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon0)
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

# Lavapipe from Mesa 25 (Debian's bookworm-backports) on Debian 12, whose own Mesa is 22.3: the
# same llvmpipe draws the sky's frames about a quarter faster there, relative to the fill-rate
# floor too (docs/performance.md), and runs pipelines Mesa 22's crashes on. SKYTUNE_SYSTEM_MESA=1
# keeps the distribution's Mesa; the tests pass on either.
codename="$( . /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-}")"
mesa_version="$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)"
if [ "$codename" = "bookworm" ] && [ "${SKYTUNE_SYSTEM_MESA:-0}" != "1" ] && ! [[ "$mesa_version" =~ ^(2[5-9]|[3-9][0-9])\. ]]; then
    echo "setup: installing Mesa's lavapipe from bookworm-backports (the distribution has $mesa_version)"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    list=/etc/apt/sources.list.d/skytune-bookworm-backports.list
    if ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
        echo "deb http://deb.debian.org/debian bookworm-backports main" | $SUDO tee "$list" >/dev/null
    fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends -t bookworm-backports mesa-vulkan-drivers >/dev/null
fi
command -v cargo >/dev/null || { echo "setup: cargo not found; install Rust (rustup) first" >&2; exit 1; }
echo "setup: system packages ready"
