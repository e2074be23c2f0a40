#!/usr/bin/env bash
# Sets up what is missing, builds, and runs every test. GPU tests run on whatever Vulkan
# adapter wgpu finds, preferring a CPU one (lavapipe); they fail if there is none, unless
# LUMAGRAPH_ALLOW_NO_GPU=1 is set.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
. scripts/env.sh
cargo test --locked --workspace "$@"
