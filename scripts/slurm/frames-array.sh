#!/usr/bin/env bash
# Splits an image sequence across a Slurm job array (docs/compositing.md#sequences):
#
#   scripts/slurm/frames-array.sh OUT RANGE TASKS GRAPH [RENDER ARGS…]
#
# RANGE is FIRST-LAST or FIRST-LASTxSTEP (as `lumagraph render --frames` takes it); the
# frames are cut into TASKS runs of consecutive frames, as even as they go, and task i
# renders its run in one process (`lumagraph render GRAPH RENDER ARGS… --frames A-BxSTEP
# --out OUT`), so the graph is built once a task and nodes with history see the frames
# before theirs within the task. Logs go to OUT/logs/.
#
# Environment: LUMAGRAPH, the lumagraph binary (default: the one on PATH, else
# target/release/lumagraph); SBATCH_ARGS, more sbatch options for every job; WAIT=1 waits
# for the array and exits with its status (non-zero where a task failed: a missing frame
# is an error naming it unless RENDER ARGS hold --skip-missing).
# OUT, GRAPH and the files the graph reads must be on a file system every node sees.
#
# Example:
#   scripts/slurm/frames-array.sh out/shot 1-100 4 shot.ron
set -euo pipefail

# Inside the array: this task's run of frames.
if [ "${1:-}" = "--task" ]; then
    out="$2" first="$3" last="$4" step="$5" tasks="$6"
    shift 6
    id="${SLURM_ARRAY_TASK_ID:?not in a Slurm array job}"
    count=$(((last - first) / step + 1))
    from=$((id * count / tasks))
    to=$(((id + 1) * count / tasks))
    if [ "$from" -ge "$to" ]; then
        echo "task $id of $tasks on $(hostname): no frames"
        exit 0
    fi
    a=$((first + from * step))
    b=$((first + (to - 1) * step))
    echo "task $id of $tasks on $(hostname): frames $a-${b}x$step"
    exec "$LUMAGRAPH" render "$@" --frames "$a-${b}x$step" --out "$out"
fi

if [ $# -lt 4 ]; then
    sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
out="$1" range="$2" tasks="$3"
shift 3
if [[ "$range" =~ ^(-?[0-9]+)-(-?[0-9]+)(x([0-9]+))?$ ]]; then
    first="${BASH_REMATCH[1]}" last="${BASH_REMATCH[2]}" step="${BASH_REMATCH[4]:-1}"
else
    echo "frames-array: RANGE is FIRST-LAST or FIRST-LASTxSTEP, not $range" >&2
    exit 2
fi
case "$tasks" in '' | *[!0-9]*)
    echo "frames-array: TASKS must be a number, not $tasks" >&2
    exit 2
    ;;
esac
if [ "$step" -lt 1 ] || [ "$last" -lt "$first" ] || [ "$tasks" -lt 1 ]; then
    echo "frames-array: $range in $tasks tasks: give FIRST <= LAST, a step and tasks of 1 or more" >&2
    exit 2
fi
# shellcheck source=scripts/slurm/lib.sh
. "$(dirname "$0")/lib.sh"
slurm_setup frames-array
mkdir -p "$out/logs"
script="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"
wait_flag=()
[ "${WAIT:-0}" = 1 ] && wait_flag=(--wait)
status=0
# shellcheck disable=SC2086 # SBATCH_ARGS is a list of options
array=$(sbatch --parsable --export=ALL ${SBATCH_ARGS:-} --job-name=lumagraph-frames \
    --array="0-$((tasks - 1))" --ntasks=1 --output="$out/logs/frames-%A_%a.log" \
    "${wait_flag[@]}" "$script" --task "$out" "$first" "$last" "$step" "$tasks" "$@") || status=$?
array="${array%%;*}"
echo "submitted frames array $array ($tasks tasks over frames $range)"
if [ "${WAIT:-0}" = 1 ]; then
    echo "array $array ended with status $status; logs in $out/logs/"
    exit "$status"
fi
