#!/usr/bin/env bash
# Installs the Python package (crates/python) from this checkout into a virtual environment,
# .venv-python (or $LUMAGRAPH_VENV), with maturin, NumPy and pytest from PyPI; with `test`,
# also runs its tests (crates/python/tests) against the command line's renders.
#   bash scripts/python.sh          # then: .venv-python/bin/python -c "import lumagraph"
#   bash scripts/python.sh test
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
. scripts/env.sh
venv=${LUMAGRAPH_VENV:-.venv-python}
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --disable-pip-version-check "maturin>=1.8,<2" "numpy>=1.21" pytest
# maturin builds with cargo, in the workspace's target folder: what `cargo build` already
# compiled is reused.
VIRTUAL_ENV="$(cd "$venv" && pwd)" "$venv/bin/maturin" develop --quiet -m crates/python/Cargo.toml
if [ "${1:-}" = test ]; then
    cargo build --locked --workspace --bins
    export LUMAGRAPH_BIN="${CARGO_TARGET_DIR:-target}/debug/lumagraph"
    "$venv/bin/python" -m pytest -q crates/python/tests
    # The example of docs/python.md.
    "$venv/bin/python" examples/python/converge.py --out "${TMPDIR:-/tmp}/lumagraph-converge-python"
fi
