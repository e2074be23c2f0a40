"""A session prints nothing on stderr but what its program prints, also on a machine
without a session runtime folder (no XDG_RUNTIME_DIR: a container, a batch job), where
Mesa's Vulkan device-select layer would have libwayland print
`error: XDG_RUNTIME_DIR is invalid or not set in the environment.` once per instance. The
module switches that layer off itself; the caller's environment is left as it comes."""

import os
import subprocess
import sys

from common import ROOT

PROGRAM = """
import sys
import lumagraph as lg
s = lg.Session("graphs/post_tonemap.ron", out=sys.argv[1])
images = s.render(1)
print("rendered", sorted(images), file=sys.stderr)
"""

# What the test clears: the runtime folder, and what would choose a device through the
# layer or switch it off already (the module then leaves it alone).
CLEARED = ("XDG_RUNTIME_DIR", "NODEVICE_SELECT", "MESA_VK_DEVICE_SELECT", "DRI_PRIME")


def test_a_session_without_xdg_runtime_dir_prints_only_its_own_lines(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in CLEARED}
    done = subprocess.run(
        [sys.executable, "-c", PROGRAM, str(tmp_path)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=600,
    )
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rendered ["), done.stderr
