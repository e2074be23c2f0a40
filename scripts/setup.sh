#!/usr/bin/env bash
# Installs what lumagraph needs on a Debian/Ubuntu machine, skipping what is already there:
# the Vulkan loader and Mesa's drivers (lavapipe, the CPU Vulkan driver, is the GPU of last
# resort and the one the tests run on), a C toolchain, Python 3 (scripts/test.sh makes a test
# mesh with it), Embree 3 (the path tracer traces its rays with it on CPU adapters; loaded at
# run time, optional), and Rust through rustup.
# Safe to run again: it only installs what is missing.
set -euo pipefail

packages=(mesa-vulkan-drivers libvulkan1 ca-certificates curl gcc libc6-dev pkg-config python3 libembree3-3)
missing=()
for p in "${packages[@]}"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: installing ${missing[*]}"
    sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null 2>&1; then
    if [ -x "$HOME/.cargo/bin/cargo" ]; then
        :
    else
        echo "setup: installing Rust with rustup"
        curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal -c rustfmt,clippy
    fi
fi
