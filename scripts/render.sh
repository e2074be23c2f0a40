#!/usr/bin/env bash
# Sets up what is missing, builds, and renders the Cornell box through the default graph
# (path tracing + G-buffer + à-trous denoise, graphs/pathtrace_denoise.ron)
# into out/ (or the folder given as the first argument). Extra arguments go to
# `lumagraph render` (e.g. --spp 1024).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
. scripts/env.sh
out="${1:-out}"
shift || true
cargo run --locked -- render graphs/pathtrace_denoise.ron --scene assets/cornell.ron --out "$out" "$@"
