# Sourced by the Slurm scripts: `slurm_setup NAME` checks that sbatch is there and sets and
# exports LUMAGRAPH, the lumagraph binary named absolutely (jobs may start in another
# folder): $LUMAGRAPH if set, else the one on PATH, else target/release/lumagraph of this
# checkout. NAME prefixes the error messages.
slurm_setup() {
    local name="$1"
    command -v sbatch >/dev/null || {
        echo "$name: sbatch not found (is Slurm's client installed? scripts/slurm/local-cluster.sh)" >&2
        exit 1
    }
    if [ -z "${LUMAGRAPH:-}" ]; then
        LUMAGRAPH="$(command -v lumagraph || true)"
        [ -n "$LUMAGRAPH" ] || LUMAGRAPH="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)/target/release/lumagraph"
    fi
    case "$LUMAGRAPH" in */*)
        if [ -d "$(dirname "$LUMAGRAPH")" ]; then
            LUMAGRAPH="$(cd "$(dirname "$LUMAGRAPH")" && pwd)/$(basename "$LUMAGRAPH")"
        fi
        ;;
    esac
    [ -x "$LUMAGRAPH" ] || {
        echo "$name: $LUMAGRAPH is not an executable (set LUMAGRAPH)" >&2
        exit 1
    }
    export LUMAGRAPH
}
