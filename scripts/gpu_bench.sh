#!/usr/bin/env bash
# Every GPU figure of docs/benchmarks.md ("On a real GPU") in one run, with the device named:
# the adapter and its ray-query support, then for the Cornell box, a mesh of 1.3 M triangles
# and the Crytek Sponza, each at 1000x1000 and 20 bounces:
#   - paths/s of the path tracer's shader variants (`lumagraph bench`): the specialized
#     shader, the general one, the megakernel against the wavefront (bench measures the one
#     the specialized shader is not), and the specialized one through the 8-wide BVH
#     (--intersector wide) with the binary BVH's beside it; traversal alone
#     (`bench --traversal`: primary and diffuse closest-hit queries, both BVHs);
#   - the wall time of a 15 000-spp render through graphs/pathtrace.ron (the figure seed
#     renderers give), or, where that would not fit the time left, the time of a shorter
#     render and its 15 000-spp time extrapolated and marked so.
#   - with MITSUBA_PYTHON (a Python that imports mitsuba 3.9.1 and drjit), Mitsuba 3's
#     paths/s on the Cornell box and the mesh, same size, bounces and spp
#     (scripts/bench/mitsuba_time.py on `lumagraph export`'s scene, scripts/bench/mesh_env.py
#     mitsuba), variant MITSUBA_VARIANT (default cuda_ad_rgb); Sponza has no Mitsuba scene.
# The last lines are a table. Meant to finish in under 8 minutes on an H100-class GPU.
#
#   LUMAGRAPH=target/release/lumagraph SPONZA=path/to/Sponza bash scripts/gpu_bench.sh [OUT]
#
# SPONZA: a folder holding Sponza.gltf (the Crytek Sponza in glTF; see docs/benchmarks.md for
# the copy used); without it the Sponza row is skipped and the closed Sponza uses
# assets/sponza-small. BUDGET: seconds for the whole script (default 450). SIZE: the image's
# side (1000). SCENES: which of "cornell cornell_seed mesh mesh_white sponza sponza_closed" to
# run (default all: ours, and beside each the seed-like one of assets/bench/, built from seed
# 000's description: the dark box, the white mesh, the closed Sponza lit by small lights).
# MESH_OBJ: an existing 1.3 M-triangle blob (else it is made with scripts/bench/mesh_env.py,
# about 30-50 s). Each bench line prints rays per path, so the seed's time can be set beside
# ours with the work per path known.
set -uo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
out=${1:-out/gpu_bench}
mkdir -p "$out"
out=$(cd "$out" && pwd)
lg=${LUMAGRAPH:-target/release/lumagraph}
budget=${BUDGET:-450}
scenes=${SCENES:-cornell cornell_seed mesh mesh_white sponza sponza_closed}
full_spp=15000
size=${SIZE:-1000}
bench_spp=${BENCH_SPP:-64}
start=$(date +%s)
left() { echo $((budget - ($(date +%s) - start))); }
log="$out/gpu_bench.log"
: >"$log"
say() { echo "$*" | tee -a "$log"; }
rows=()

say "== gpu_bench $(date -u +%Y-%m-%dT%H:%M:%SZ), lumagraph $("$lg" --version 2>/dev/null)"
if command -v nvidia-smi >/dev/null 2>&1; then
    nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,power.limit --format=csv,noheader 2>&1 | tee -a "$log"
fi
say "== adapters"
"$lg" adapters 2>&1 | tee -a "$log"
if command -v vulkaninfo >/dev/null 2>&1; then
    say "== vulkaninfo: ray tracing extensions"
    vulkaninfo 2>/dev/null | grep -E 'deviceName|VK_KHR_(ray_query|acceleration_structure|ray_tracing_pipeline)' | sort -u | tee -a "$log"
fi

# Whether an adapter has ray queries (then the GPU's, which render chooses over lavapipe).
ray_queries=""
"$lg" adapters 2>/dev/null | grep -q 'ray queries: yes' && ray_queries=yes

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
hdr="$repo/assets/hdri/venice_sunset_1k.hdr"

# The Cornell box of the reference suite at 1000x1000.
sed -e "s/width: 256, height: 256/width: $size, height: $size/" assets/cornell.ron >"$work/cornell.ron"

# The seed-like box (assets/bench/cornell_seed.ron: dark gold, single-channel side walls).
sed -e "s/width: 1000, height: 1000/width: $size, height: $size/" assets/bench/cornell_seed.ron >"$work/cornell_seed.ron"

# The mesh scene (assets/bench/mesh_env.ron) with its blob subdivided to 1 310 720 triangles,
# and the seed-like white mesh (assets/bench/mesh_white.ron) of the same blob.
mesh_obj=${MESH_OBJ:-$work/blob8.obj}
[[ "$mesh_obj" = /* ]] || mesh_obj="$repo/$mesh_obj"
if [[ " $scenes " == *" mesh"* ]] && [ ! -f "$mesh_obj" ]; then
    python3 scripts/bench/mesh_env.py make "$mesh_obj" --level 8 >>"$log" 2>&1 &
    mesh_pid=$!
fi
sed -e "s|path: \"blob.obj\"|path: \"$mesh_obj\"|" -e "s|\"../hdri/venice_sunset_1k.hdr\"|\"$hdr\"|" \
    -e "s/width: 256, height: 256/width: $size, height: $size/" assets/bench/mesh_env.ron >"$work/mesh.ron"
sed -e "s|path: \"blob8.obj\"|path: \"$mesh_obj\"|" -e "s|\"../hdri/venice_sunset_1k.hdr\"|\"$hdr\"|" \
    -e "s/width: 1000, height: 1000/width: $size, height: $size/" assets/bench/mesh_white.ron >"$work/mesh_white.ron"

# The seed-like closed Sponza (assets/bench/sponza_closed.ron), with SPONZA's glTF where given.
sponza_gltf="$repo/assets/sponza-small/Sponza.gltf"
[ -n "${SPONZA:-}" ] && [ -f "$SPONZA/Sponza.gltf" ] && sponza_gltf="$(cd "$SPONZA" && pwd)/Sponza.gltf"
sed -e "s|\"../sponza-small/Sponza.gltf\"|\"$sponza_gltf\"|" \
    -e "s/width: 1000, height: 1000/width: $size, height: $size/" assets/bench/sponza_closed.ron >"$work/sponza_closed.ron"

# Sponza: its glTF materials and first camera, the Venice map and a low sun.
if [ -n "${SPONZA:-}" ] && [ -f "$SPONZA/Sponza.gltf" ]; then
    sponza=$(cd "$SPONZA" && pwd)
    cat >"$work/sponza.ron" <<EOF
(
    version: 2,
    camera: Gltf(shape: "sponza", index: 0),
    shapes: [Mesh(name: "sponza", path: "$sponza/Sponza.gltf")],
    lights: [Directional(direction: (-0.25, -1.0, 0.3), irradiance: (12.0, 11.0, 9.5))],
    environment: Map(path: "$hdr", intensity: 1.0),
    render: (width: $size, height: $size, max_bounces: 20, spp: 64, seed: 0),
)
EOF
fi

# $1 scene name: bench's shader variants, then the render (15 000 spp, or fewer and
# extrapolated where the time left is short).
run_scene() {
    local name=$1 scene="$work/$1.ron"
    [ -f "$scene" ] || { say "== $name: skipped (no scene)"; return; }
    say "== $name: bench ($bench_spp spp per run, best of 3)"
    timeout $(( $(left) > 60 ? $(left) : 60 )) "$lg" bench --scene "$scene" --spp "$bench_spp" --runs 3 2>&1 | tee -a "$log" | tee "$work/bench.txt"
    # The specialized shader's figure (the first paths/s on the bench's lines) and the
    # general shader's.
    local mps general
    mps=$(grep -m1 -oE '[0-9.]+ M paths/s' "$work/bench.txt" | grep -oE '^[0-9.]+')
    local rpp
    rpp=$(grep -m1 -oE '[0-9.]+ rays/path' "$work/bench.txt" | grep -oE '^[0-9.]+')
    general=$(grep -m1 -E '^  general ' "$work/bench.txt" | grep -oE '[0-9.]+ M paths/s' | grep -oE '^[0-9.]+')
    # The megakernel against the wavefront, where the scene allows the wavefront.
    local front
    front=$(grep -m1 -oE 'megakernel / wavefront: [0-9.]+x' "$work/bench.txt" | grep -oE '[0-9.]+x')
    [ -n "$mps" ] || { say "== $name: bench printed no paths/s"; rows+=("| $name | failed | | | | | | | | | |"); return; }
    # The 8-wide BVH (--intersector wide), which bench measures with the binary BVH after it:
    # two pairs for the wide-against-binary ratio (the binary figure above, and this one).
    say "== $name: bench with the 8-wide BVH (--intersector wide), then the binary one"
    timeout $(( $(left) > 60 ? $(left) : 60 )) "$lg" bench --scene "$scene" --intersector wide \
        --spp "$bench_spp" --runs 3 --specialized-only 2>&1 | tee -a "$log" | tee "$work/bench2.txt"
    local wide binary2 ratio=""
    wide=$(grep -m1 -oE '[0-9.]+ M paths/s' "$work/bench2.txt" | grep -oE '^[0-9.]+')
    binary2=$(grep -m1 -E '^  binary BVH ' "$work/bench2.txt" | grep -oE '[0-9.]+ M paths/s' | grep -oE '^[0-9.]+')
    [ -n "$wide" ] && [ -n "$binary2" ] && ratio=$(awk -v w="$wide" -v a="$mps" -v b="$binary2" \
        'BEGIN { printf "%.2f, %.2f", w / a, w / b }')
    # Traversal alone: closest-hit queries through both BVHs, no shading.
    say "== $name: traversal alone (bench --traversal)"
    timeout $(( $(left) > 60 ? $(left) : 60 )) "$lg" bench --scene "$scene" --traversal --runs 3 2>&1 | tee -a "$log"
    # On a device with ray queries the specialized shader traces through them: the WGSL BVH
    # beside it, for the comparison.
    if [ -n "$ray_queries" ]; then
        say "== $name: bench without ray queries (LUMAGRAPH_RAY_QUERY=off: the WGSL BVH)"
        LUMAGRAPH_RAY_QUERY=off timeout $(( $(left) > 60 ? $(left) : 60 )) "$lg" bench --scene "$scene" \
            --spp "$bench_spp" --runs 3 --specialized-only 2>&1 | tee -a "$log"
    fi
    # Mitsuba 3 on the same scene, where MITSUBA_PYTHON names a Python with it.
    local mitsuba=""
    if [ -n "${MITSUBA_PYTHON:-}" ] && [[ "$name" == cornell* || "$name" == mesh ]]; then
        local variant=${MITSUBA_VARIANT:-cuda_ad_rgb} json=""
        say "== $name: Mitsuba 3 ($variant, $bench_spp spp, best of 3)"
        if [[ "$name" == cornell* ]]; then
            "$lg" export "$scene" --out "$work/${name}_export" >/dev/null 2>&1
            json=$(timeout 300 "$MITSUBA_PYTHON" scripts/bench/mitsuba_time.py "$work/${name}_export" \
                --spp "$bench_spp" --runs 3 --variant "$variant" 2>>"$log" | tail -n 1)
        else
            json=$(timeout 300 "$MITSUBA_PYTHON" scripts/bench/mesh_env.py mitsuba "$mesh_obj" --spp "$bench_spp" \
                --runs 3 --variant "$variant" --width "$size" --height "$size" 2>>"$log" | tail -n 1)
        fi
        say "$json"
        mitsuba=$(python3 -c 'import json, sys; print("%.1f" % (json.loads(sys.argv[1])["paths_per_s"] / 1e6))' "$json" 2>/dev/null)
        [ -n "$mitsuba" ] && mitsuba="$mitsuba ($(awk -v a="$mps" -v b="$mitsuba" 'BEGIN { printf "%.2f", a / b }')x)"
    fi
    # Predicted wall time at 15 000 spp, with 15 % for the graph's other passes.
    local predicted spp note
    predicted=$(awk -v m="$mps" -v s=$full_spp 'BEGIN { printf "%d", 1.15 * 1e6 * s / (m * 1e6) + 1 }')
    # The time left, shared with the scenes still to run.
    local share=$(( ($(left) - 20) / remaining ))
    if [ "$predicted" -le "$share" ]; then
        spp=$full_spp
        note="measured"
    else
        spp=$(awk -v m="$mps" -v t="$share" 'BEGIN { s = int(t * m / 1.15 / 16) * 16; if (s < 64) s = 64; print s }')
        note="extrapolated from $spp spp"
    fi
    say "== $name: render $spp spp (predicted $predicted s for $full_spp)"
    mkdir -p "$out/$name"
    timeout $(( $(left) > 30 ? $(left) : 30 )) "$lg" render graphs/pathtrace.ron --scene "$scene" --spp "$spp" \
        --set pathtrace.samples_per_frame=16 --out "$out/$name" 2>&1 | tee -a "$log" | tee "$work/render.txt"
    local line secs paths
    line=$(grep -m1 -E '^rendered ' "$work/render.txt")
    secs=$(echo "$line" | grep -oE 'in [0-9.]+ s' | grep -oE '[0-9.]+')
    paths=$(echo "$line" | grep -oE '[0-9.]+ M paths/s' | grep -oE '^[0-9.]+')
    if [ -z "$secs" ]; then
        rows+=("| $name | $mps | $rpp | $front | $wide | $ratio | $general | $mitsuba | render failed | | |")
        return
    fi
    local at_full
    at_full=$(awk -v t="$secs" -v s="$spp" -v f=$full_spp 'BEGIN { printf "%.1f", t * f / s }')
    rows+=("| $name | $mps | $rpp | $front | $wide | $ratio | $general | $mitsuba | $paths | $at_full s | $note |")
}

remaining=$(wc -w <<<"$scenes")
for s in $scenes; do
    if [[ "$s" == mesh* ]] && [ -n "${mesh_pid:-}" ]; then
        wait "$mesh_pid" || say "== mesh: making the blob failed"
        mesh_pid=""
    fi
    run_scene "$s"
    remaining=$((remaining - 1))
done

say ""
say "== $(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null || "$lg" adapters 2>/dev/null | head -1), ${size}x$size, 20 bounces, $full_spp spp, total $(( $(date +%s) - start )) s"
say "| scene | bench, specialized, M paths/s | rays/path | megakernel / wavefront | 8-wide BVH | wide / binary (two pairs) | general | Mitsuba 3, M paths/s (lumagraph / Mitsuba) | render, M paths/s | wall time to $full_spp spp | |"
say "|---|---|---|---|---|---|---|---|---|---|---|"
for r in "${rows[@]}"; do say "$r"; done
