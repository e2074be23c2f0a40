"""What the tests share: the repository's folder, the graph and scene they render, and
the command line built from the same checkout (LUMAGRAPH_BIN, set by
`bash scripts/python.sh test`)."""

import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
GRAPH = ROOT / "graphs" / "pathtrace.ron"
SCENE = ROOT / "assets" / "cornell.ron"


def cli():
    """The command line to compare with; the test is skipped without one."""
    path = os.environ.get("LUMAGRAPH_BIN")
    if not path:
        pytest.skip("LUMAGRAPH_BIN is not set (scripts/python.sh test sets it)")
    return str(ROOT / path) if not os.path.isabs(path) else path
