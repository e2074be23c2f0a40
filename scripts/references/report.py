#!/usr/bin/env python3
"""The Mitsuba reference suite as a table and a picture, from a lumagraph build.

For every scene of tests/scenes/ (references in tests/reference/suite/, see make.py): renders
it with `lumagraph render graphs/pathtrace.ron` at 256 and 1024 spp, and prints the Markdown
table of docs/pathtracer.md: relMSE at 256 spp against the reference and as a multiple of
Mitsuba's own at 256 spp, and the worst 32x32 block-mean deviation at 1024 spp (blocks and
channels whose reference mean exceeds 0.02), as tests/mitsuba_suite.rs measures them. Writes
docs/images/mitsuba_suite.png: per scene, lumagraph at 1024 spp | Mitsuba's reference |
(lumagraph - reference) / reference from -10 % (blue) to +10 % (red).

  .venv-mitsuba/bin/python scripts/references/report.py [--lumagraph target/release/lumagraph]

Scene names restrict it to those scenes (then give `--image`), e.g. the media figure:

  .venv-mitsuba/bin/python scripts/references/report.py media_absorbing_glass \
      media_scattering --image docs/images/media.png
"""
import argparse
import json
import os
import subprocess
import tempfile

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def load_exr(path):
    import mitsuba as mi
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def render(lumagraph, scene, spp, out):
    subprocess.run([lumagraph, "render", os.path.join(ROOT, "graphs", "pathtrace.ron"),
                    "--scene", scene, "--spp", str(spp), "--out", out],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return load_exr(os.path.join(out, "render.exr"))


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 1e-2)))


def worst_block(x, ref, block=32, floor=0.02):
    h, w, _ = ref.shape
    bx = x.reshape(h // block, block, w // block, block, 3).mean((1, 3))
    br = ref.reshape(h // block, block, w // block, block, 3).mean((1, 3))
    dev = np.where(br > floor, (bx - br) / np.maximum(br, 1e-12), 0.0)
    i = np.unravel_index(np.abs(dev).argmax(), dev.shape)
    return float(dev[i])


def display(x):
    return np.clip(x, 0, 1) ** (1 / 2.2)


def heat(x, ref):
    d = np.clip((x - ref) / np.maximum(ref, 1e-3), -0.1, 0.1).mean(-1) / 0.1
    out = np.ones(d.shape + (3,))
    out[..., 0] = np.where(d < 0, 1 + d, 1)
    out[..., 1] = 1 - np.abs(d)
    out[..., 2] = np.where(d > 0, 1 - d, 1)
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--lumagraph", default=os.path.join(ROOT, "target", "release", "lumagraph"))
    p.add_argument("scenes", nargs="*", help="scene names in tests/scenes (default: all)")
    p.add_argument("--image", default=os.path.join(ROOT, "docs", "images", "mitsuba_suite.png"))
    a = p.parse_args()
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    with open(os.path.join(ROOT, "tests", "scenes", "suite.json")) as f:
        manifest = json.load(f)["scenes"]
    names = a.scenes or sorted(f[:-4] for f in os.listdir(os.path.join(ROOT, "tests", "scenes"))
                               if f.endswith(".ron"))
    print("| scene | Mitsuba plugins | relMSE at 256 spp | × Mitsuba's | worst block at 1024 spp |")
    print("|---|---|---|---|---|")
    tiles = []
    for name in names:
        entry = manifest.get(name, {})
        refname = entry.get("reference", name)
        ref = load_exr(os.path.join(ROOT, "tests", "reference", "suite", refname + ".exr"))
        with open(os.path.join(ROOT, "tests", "reference", "suite", refname + ".json")) as f:
            meta = json.load(f)
        scene = os.path.join(ROOT, "tests", "scenes", name + ".ron")
        with tempfile.TemporaryDirectory() as tmp:
            at256 = render(a.lumagraph, scene, 256, tmp)
            at1024 = render(a.lumagraph, scene, 1024, tmp)
        r = relmse(at256, ref)
        theirs = meta["mitsuba_relmse_256"]["mean"]
        plugins = ", ".join(sorted(set(meta["plugins"].values())))
        note = " (model difference)" if "model_difference" in entry else ""
        if refname != name:
            note = f" (held to {refname}'s reference)"
        print(f"| `{name}`{note} | {plugins} | {r:.2e} | {r / theirs:.2f} | "
              f"{worst_block(at1024, ref) * 100:+.2f} % |", flush=True)
        tiles.append(np.concatenate([display(at1024), display(ref), heat(at1024, ref)], 1))
    while len(tiles) % 2:
        tiles.append(np.zeros_like(tiles[0]))
    gap = np.ones((tiles[0].shape[0], 8, 3))
    rows = [np.concatenate([tiles[i], gap, tiles[i + 1]], 1) for i in range(0, len(tiles), 2)]
    sep = np.ones((8, rows[0].shape[1], 3))
    image = np.concatenate(sum(([r, sep] for r in rows), [])[:-1], 0)
    os.makedirs(os.path.dirname(a.image), exist_ok=True)
    mi.Bitmap((image * 255 + 0.5).astype(np.uint8)).write(a.image)
    print(f"\nwrote {os.path.relpath(a.image, ROOT)}: per scene, lumagraph 1024 spp | Mitsuba | "
          "difference (blue -10 % .. red +10 %); scenes in the table's order, two per row")


if __name__ == "__main__":
    main()
