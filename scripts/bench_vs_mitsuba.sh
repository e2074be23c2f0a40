#!/usr/bin/env bash
# lumagraph and Mitsuba 3 side by side, in one run on this machine: the Cornell box
# (assets/cornell.ron) and the mesh benchmark scene (assets/bench/mesh_env.ron: an
# 81 920-triangle mesh under an environment map), and with SPONZA set to a folder holding
# the Crytek Sponza in glTF, that real scene as both renderers read it: its materials
# reduced to diffuse base colour textures with their alpha cut-outs (`diffuse: true`; the
# scene of tests/scenes/sponza_diffuse.ron at 256x160 with every texture), which Mitsuba
# renders with `volpath` (shadow rays through the cut-outs). Prints both renderers' paths/s
# and their ratio for each. Only a ratio taken in one run means something on a shared
# machine; the load average is printed before and after.
#
#   [SPONZA=path/to/Sponza] scripts/bench_vs_mitsuba.sh [SPP]
#
# It builds and runs target/release/lumagraph, or runs the binary LUMAGRAPH names (use a
# release build: with host intersection, Rust code runs on the host between the kernel's
# steps, and a dev build compiles it at opt-level 1).
# lumagraph's figure is `bench`'s "specialized" line (the shader the renderer uses). Mitsuba
# 3.9.1 (variant llvm_ad_rgb) is taken from MITSUBA_PYTHON, by default
# .venv-mitsuba/bin/python (python3 -m venv .venv-mitsuba && .venv-mitsuba/bin/pip install
# mitsuba==3.9.1 numpy; Debian also needs `apt-get install libllvm19`). The Cornell box goes
# to Mitsuba through `lumagraph export` and scripts/references/make.py, as in the reference
# suite (scripts/bench/mitsuba_time.py).
set -euo pipefail
cd "$(dirname "$0")/.."
spp=${1:-64}
py=${MITSUBA_PYTHON:-.venv-mitsuba/bin/python}
[ -f assets/bench/blob.obj ] || python3 scripts/bench/mesh_env.py make assets/bench/blob.obj
. scripts/env.sh
if [ -z "${LUMAGRAPH:-}" ]; then
    cargo build --release -q
fi
lg_bin=${LUMAGRAPH:-target/release/lumagraph}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"

specialized() { awk '$1 == "specialized" && $3 == "M" {print $2}'; }
paths() { python3 -c 'import json, sys; print(json.loads(sys.stdin.read().splitlines()[-1])["paths_per_s"] / 1e6)'; }

$lg_bin export assets/cornell.ron --out "$tmp/cornell" > /dev/null
out=$($lg_bin bench --scene assets/cornell.ron --spp "$spp" --runs 3)
echo "$out"
lg_c=$(specialized <<< "$out")
out=$("$py" scripts/bench/mitsuba_time.py "$tmp/cornell" --spp "$spp" --runs 3)
echo "$out"
mi_c=$(paths <<< "$out")
out=$($lg_bin bench --scene assets/bench/mesh_env.ron --spp "$spp" --runs 3)
echo "$out"
lg_m=$(specialized <<< "$out")
out=$("$py" scripts/bench/mesh_env.py mitsuba assets/bench/blob.obj --spp "$spp" --runs 3)
echo "$out"
mi_m=$(paths <<< "$out")
rows=("Cornell box:$lg_c:$mi_c" "mesh scene:$lg_m:$mi_m")
if [ -n "${SPONZA:-}" ]; then
    sponza=$(cd "$SPONZA" && pwd)
    sed -e "s|../../assets/sponza-small/Sponza.gltf|$sponza/Sponza.gltf|" \
        -e "s|../../assets/hdri/|$PWD/assets/hdri/|" \
        -e "s|width: 128, height: 128|width: 256, height: 160|" \
        tests/scenes/sponza_diffuse.ron > "$tmp/sponza.ron"
    $lg_bin export "$tmp/sponza.ron" --out "$tmp/sponza" > /dev/null
    out=$($lg_bin bench --scene "$tmp/sponza.ron" --spp "$spp" --runs 3 --specialized-only)
    echo "$out"
    lg_s=$(specialized <<< "$out")
    out=$("$py" scripts/bench/mitsuba_time.py "$tmp/sponza" --spp "$spp" --runs 3)
    echo "$out"
    mi_s=$(paths <<< "$out")
    rows+=("Crytek Sponza (diffuse, cut-outs):$lg_s:$mi_s")
fi
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
for row in "${rows[@]}"; do
    IFS=: read -r name lg mi <<< "$row"
    python3 -c "lg, mi = $lg, $mi; print(f'$name, $spp spp: lumagraph {lg:.3f} M paths/s, Mitsuba {mi:.3f} M paths/s: {lg / mi:.3f}x')"
done
