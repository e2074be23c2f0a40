"""Blender's default view of a render, through PyOpenColorIO: the reference for
graphs/view_agx.ron.

Reads tests/reference/cornell_ref.exr (linear Rec. 709, the Cornell box as Mitsuba 3
renders it) with OpenEXR's Python bindings, applies Blender 4.2's config (the one
scripts/setup.sh unpacks, or $LUMAGRAPH_BLENDER_OCIO) from its scene-linear space
("Linear Rec.709") to the sRGB display's AgX view, as Blender shows a render by
default, and writes tests/color/blender_agx_cornell.png: 8 bits, each value
round(clamp(v, 0, 1) * 255), alpha 255.

    python3 -m venv .venv-ocio
    .venv-ocio/bin/pip install opencolorio==2.6.0 OpenEXR numpy pillow
    .venv-ocio/bin/python scripts/ocio/blender_agx.py

Not run by CI: the PNG is committed; tests/post/ocio.rs renders the graph and compares.
"""
from __future__ import annotations

import os
from pathlib import Path

for _var in ("OCIO", "OCIO_ACTIVE_DISPLAYS", "OCIO_ACTIVE_VIEWS", "OCIO_INACTIVE_COLORSPACES"):
    os.environ.pop(_var, None)

import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402
import PyOpenColorIO as OCIO  # noqa: E402
from PIL import Image  # noqa: E402

from reference import blender_config  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
SOURCE = REPO / "tests" / "reference" / "cornell_ref.exr"
OUT = REPO / "tests" / "color" / "blender_agx_cornell.png"


def main() -> None:
    config = OCIO.Config.CreateFromFile(str(blender_config()))
    with OpenEXR.File(str(SOURCE), separate_channels=True) as f:
        rgb = np.stack([f.channels()[c].pixels.astype(np.float32) for c in "RGB"], axis=-1)
    processor = config.getProcessor("Linear Rec.709", "sRGB", "AgX", OCIO.TRANSFORM_DIR_FORWARD)
    buf = np.ascontiguousarray(rgb.reshape(-1, 3)).copy()
    processor.getDefaultCPUProcessor().applyRGB(buf)
    out = np.round(np.clip(buf.reshape(rgb.shape), 0.0, 1.0) * 255.0).astype(np.uint8)
    alpha = np.full(out.shape[:2] + (1,), 255, dtype=np.uint8)
    Image.fromarray(np.concatenate([out, alpha], axis=-1), "RGBA").save(OUT, optimize=True)
    print(f"PyOpenColorIO {OCIO.__version__}, {blender_config()}: wrote "
          f"{OUT.relative_to(REPO)} ({out.shape[1]}x{out.shape[0]})")


if __name__ == "__main__":
    main()
