#!/usr/bin/env bash
# lumagraph and Mitsuba 3 side by side on the mesh benchmark scene (assets/bench/mesh_env.ron:
# an 81 920-triangle mesh under an environment map), in one run on this machine; prints
# both paths/s and their ratio. Only a ratio taken in one run means something on a shared
# machine.
#
#   scripts/bench_vs_mitsuba.sh [SPP]
#
# Mitsuba 3.9.1 (variant llvm_ad_rgb) is taken from MITSUBA_PYTHON, by default
# .venv-mitsuba/bin/python (python3 -m venv .venv-mitsuba && .venv-mitsuba/bin/pip install
# mitsuba==3.9.1; Debian also needs `apt-get install libllvm19`).
set -euo pipefail
cd "$(dirname "$0")/.."
spp=${1:-64}
py=${MITSUBA_PYTHON:-.venv-mitsuba/bin/python}
[ -f assets/bench/blob.obj ] || python3 scripts/bench/mesh_env.py make assets/bench/blob.obj
. scripts/env.sh
cargo build --release -q
lg=$(target/release/lumagraph bench --scene assets/bench/mesh_env.ron --spp "$spp" --runs 3 \
    | tee /dev/stderr | awk '$1 == "specialized" && $3 == "M" {print $2}')
mi=$("$py" scripts/bench/mesh_env.py mitsuba assets/bench/blob.obj --spp "$spp" --runs 3 \
    | tee /dev/stderr | python3 -c 'import json, sys; print(json.load(sys.stdin)["paths_per_s"] / 1e6)')
python3 -c "lg, mi = $lg, $mi; print(f'mesh scene, {$spp} spp: lumagraph {lg:.3f} M paths/s, Mitsuba {mi:.3f} M paths/s: {lg / mi:.3f}x')"
