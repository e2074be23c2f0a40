#!/usr/bin/env bash
# Sets up what is missing, builds, and runs every test. GPU tests run on whatever Vulkan
# adapter wgpu finds, preferring a CPU one (lavapipe); they fail if there is none, unless
# LUMAGRAPH_ALLOW_NO_GPU=1 is set.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
. scripts/env.sh
# The mesh of assets/bench/mesh_env.ron (a suite scene of tests/denoise/suite.rs) is made, not stored.
[ -f assets/bench/blob.obj ] || python3 scripts/bench/mesh_env.py make assets/bench/blob.obj
cargo test --locked --workspace "$@"
# The Python package's tests, when every test runs (no filter given).
if [ $# -eq 0 ]; then
    bash scripts/python.sh test
fi
