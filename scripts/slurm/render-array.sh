#!/usr/bin/env bash
# Splits one render across a Slurm job array and merges it (docs/distributed.md):
#
#   scripts/slurm/render-array.sh OUT SPP TASKS GRAPH [RENDER ARGS…]
#
# submits an array of TASKS jobs; task i renders samples i·SPP/TASKS..(i+1)·SPP/TASKS
# (`lumagraph render GRAPH RENDER ARGS… --samples A..B --out OUT/parts`), then a merge job
# that starts when every task succeeded (`lumagraph merge OUT/parts/… --out OUT`). SPP must
# be a multiple of TASKS times the graph's samples per frame. Logs go to OUT/logs/.
#
# Environment: LUMAGRAPH, the lumagraph binary (default: the one on PATH, else
# target/release/lumagraph); SBATCH_ARGS, more sbatch options for every job (a partition,
# a time limit, --gres=gpu:1); WAIT=1 waits for the merge job and exits with its status.
# OUT, GRAPH and the paths in RENDER ARGS must be on a file system every node sees.
#
# Example:
#   scripts/slurm/render-array.sh out/split 1024 4 graphs/pathtrace_denoise.ron \
#       --scene assets/cornell.ron
set -euo pipefail

# Inside the array: this task's share of the samples.
if [ "${1:-}" = "--task" ]; then
    out="$2" spp="$3" tasks="$4"
    shift 4
    id="${SLURM_ARRAY_TASK_ID:?not in a Slurm array job}"
    per=$((spp / tasks))
    first=$((id * per))
    echo "task $id of $tasks on $(hostname): samples $first..$((first + per))"
    exec "$LUMAGRAPH" render "$@" --samples "$first..$((first + per))" --out "$out/parts"
fi
# The merge job: every task's partial render, by name (a missing one is an error).
if [ "${1:-}" = "--merge" ]; then
    out="$2" spp="$3" tasks="$4"
    per=$((spp / tasks))
    parts=()
    for ((i = 0; i < tasks; i++)); do
        parts+=("$out/parts/samples-$((i * per))-$(((i + 1) * per)).partial")
    done
    exec "$LUMAGRAPH" merge "${parts[@]}" --out "$out"
fi

if [ $# -lt 4 ]; then
    sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
out="$1" spp="$2" tasks="$3"
shift 3
case "$spp$tasks" in *[!0-9]*)
    echo "render-array: SPP and TASKS must be numbers, not $spp and $tasks" >&2
    exit 2
    ;;
esac
if [ "$tasks" -lt 1 ] || [ $((spp % tasks)) -ne 0 ]; then
    echo "render-array: $spp samples do not split into $tasks equal ranges" >&2
    exit 2
fi
# shellcheck source=scripts/slurm/lib.sh
. "$(dirname "$0")/lib.sh"
slurm_setup render-array
mkdir -p "$out/logs" "$out/parts"
script="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"
# shellcheck disable=SC2086 # SBATCH_ARGS is a list of options
array=$(sbatch --parsable --export=ALL ${SBATCH_ARGS:-} --job-name=lumagraph-render \
    --array="0-$((tasks - 1))" --ntasks=1 --output="$out/logs/render-%A_%a.log" \
    "$script" --task "$out" "$spp" "$tasks" "$@")
array="${array%%;*}"
echo "submitted render array $array ($tasks tasks of $((spp / tasks)) samples)"
wait_flag=()
[ "${WAIT:-0}" = 1 ] && wait_flag=(--wait)
status=0
# shellcheck disable=SC2086
merge=$(sbatch --parsable --export=ALL ${SBATCH_ARGS:-} --job-name=lumagraph-merge \
    --dependency="afterok:$array" --kill-on-invalid-dep=yes --ntasks=1 \
    --output="$out/logs/merge-%j.log" "${wait_flag[@]}" \
    "$script" --merge "$out" "$spp" "$tasks") || status=$?
merge="${merge%%;*}"
echo "submitted merge job $merge (after every task of $array succeeded)"
if [ "${WAIT:-0}" = 1 ]; then
    echo "merge job $merge ended with status $status; its log:"
    cat "$out/logs/merge-$merge.log" 2>/dev/null || echo "(no log: a task failed, see $out/logs/)"
    exit "$status"
fi
