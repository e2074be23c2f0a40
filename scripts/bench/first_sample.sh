#!/usr/bin/env bash
# Time to the first sample: lumagraph against Mitsuba 3 on the same scenes, whole processes
# run in turn (lumagraph, Mitsuba, lumagraph, ...), medians printed (docs/benchmarks.md,
# "Time to the first sample").
#
#   SPONZA=path/to/Sponza [RUNS=5] [SPF=4] scripts/bench/first_sample.sh
#
# Scenes: the Crytek Sponza as scripts/bench_vs_mitsuba.sh gives it to both renderers
# (diffuse base colours with alpha cut-outs, 256x160; skipped without SPONZA), and a
# 1.3 M-triangle white mesh under the Venice map (assets/bench/mesh_white.ron at 256x256:
# the blob of scripts/bench/mesh_env.py subdivided 8 times, made once into out/first_sample/).
# lumagraph: `render graphs/pathtrace.ron --spp SPF --set pathtrace.samples_per_frame=SPF`,
# its own `first sample:` line (the first frame kept, SPF samples per pixel) and the whole
# process; Mitsuba (MITSUBA_PYTHON, default .venv-mitsuba/bin/python; llvm_ad_rgb):
# scripts/bench/mitsuba_first.py, loading the same files and rendering 1 sample per pixel,
# its `load_s + first_s` and the whole process. LUMAGRAPH names the binary (default
# target/release/lumagraph, built here). The load average is printed before and after:
# on a shared machine only figures taken in turn mean something.
set -euo pipefail
cd "$(dirname "$0")/../.."
runs=${RUNS:-5}
spf=${SPF:-4}
py=${MITSUBA_PYTHON:-.venv-mitsuba/bin/python}
. scripts/env.sh
if [ -z "${LUMAGRAPH:-}" ]; then
    cargo build --release -q
fi
lg=${LUMAGRAPH:-target/release/lumagraph}
dir=out/first_sample
mkdir -p "$dir"
[ -f "$dir/blob8.obj" ] || python3 scripts/bench/mesh_env.py make "$dir/blob8.obj" --level 8
sed -e "s|path: \"blob8.obj\"|path: \"$PWD/$dir/blob8.obj\"|" \
    -e "s|../hdri/|$PWD/assets/hdri/|" \
    -e 's|width: 1000, height: 1000, max_bounces: 20, spp: 15000|width: 256, height: 256, max_bounces: 20, spp: 64|' \
    assets/bench/mesh_white.ron > "$dir/mesh.ron"
scenes=("mesh:$dir/mesh.ron:--obj $PWD/$dir/blob8.obj")
if [ -n "${SPONZA:-}" ]; then
    sponza=$(cd "$SPONZA" && pwd)
    sed -e "s|../../assets/sponza-small/Sponza.gltf|$sponza/Sponza.gltf|" \
        -e "s|../../assets/hdri/|$PWD/assets/hdri/|" \
        -e "s|width: 128, height: 128|width: 256, height: 160|" \
        tests/scenes/sponza_diffuse.ron > "$dir/sponza.ron"
    scenes=("sponza:$dir/sponza.ron:" "${scenes[@]}")
fi
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
median() { python3 -c 'import statistics, sys; v = [float(x) for x in sys.stdin.read().split()]; print(f"{statistics.median(v):.3f} (min {min(v):.3f}, max {max(v):.3f}, {len(v)} runs)")'; }
# wall LOG CMD...: runs CMD with its output in LOG and prints its wall seconds.
wall() {
    local log=$1 t0 t1
    shift
    t0=$(date +%s.%N)
    "$@" > "$log" 2>&1
    t1=$(date +%s.%N)
    python3 -c "print($t1 - $t0)"
}
for s in "${scenes[@]}"; do
    IFS=: read -r name scene mi_args <<< "$s"
    [ -d "$dir/${name}_export" ] || "$lg" export "$scene" --out "$dir/${name}_export" > /dev/null
    lg_wall=() lg_first=() mi_wall=() mi_first=()
    for _ in $(seq "$runs"); do
        lg_wall+=("$(wall "$dir/$name.log" "$lg" render graphs/pathtrace.ron --scene "$scene" \
            --spp "$spf" --set "pathtrace.samples_per_frame=$spf" --out "$dir/$name")")
        lg_first+=("$(awk '$1 == "first" && $2 == "sample:" {print $3 / 1000}' "$dir/$name.log")")
        # shellcheck disable=SC2086
        mi_wall+=("$(wall "$dir/$name.mitsuba.log" "$py" scripts/bench/mitsuba_first.py "$dir/${name}_export" $mi_args)")
        mi_first+=("$(python3 -c 'import json, sys; d = json.loads(open(sys.argv[1]).read().splitlines()[-1]); print(d["load_s"] + d["first_s"])' "$dir/$name.mitsuba.log")")
    done
    echo "$name: lumagraph first sample ($spf spp) $(echo "${lg_first[@]}" | median) s, whole process $(echo "${lg_wall[@]}" | median) s"
    echo "$name: Mitsuba load + compile + 1 spp $(echo "${mi_first[@]}" | median) s, whole process $(echo "${mi_wall[@]}" | median) s"
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
