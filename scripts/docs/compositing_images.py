"""Makes the pictures of docs/compositing.md from the OpenEXR project's sample images
(`../shared/assets/openexr-images`, or the folder given), through lumagraph's Python
package (`bash scripts/python.sh` installs it into .venv-python):

    .venv-python/bin/python scripts/docs/compositing_images.py [IMAGES]

- compositing_beachball_layers.png: frame 1 of Beachball/multipart.####.exr read three
  ways: the colour layer (display window, 2048×1556), the depth layer (`layer: depth`,
  scalar), the forward motion (`layer: forward`, vector: its spread, u in red, v in
  green);
- compositing_display_window.png: DisplayWindow/t08.exr (a 400×300 data window at (30, 40)
  in a 501×401 display window) as read now, beside the data window alone;
- compositing_chromaticities.png: Chromaticities/XYZ.exr read as if it were Rec. 709,
  read converted from its primaries, and Chromaticities/Rec709.exr (the same picture)."""

import pathlib
import sys
import tempfile

import numpy as np

import lumagraph as lg

ROOT = pathlib.Path(__file__).resolve().parents[2]
IMAGES = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ROOT.parent / "shared" / "assets" / "openexr-images").resolve()
OUT = ROOT / "docs" / "images"


def srgb(x):
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def shrink(a, f):
    h, w = (a.shape[0] // f) * f, (a.shape[1] // f) * f
    a = a[:h, :w]
    return a.reshape(h // f, f, w // f, f, -1).mean(axis=(1, 3))


def read(path, layer="", port="color", frame=None):
    """The image ImageInput reads of `path` (its `layer`) on `port`, as an (h, w, 4) array."""
    g = lg.Graph()
    g.add_node("ImageInput", "in", path=str(path), layer=layer)
    g.add_node("Output", "out", path="x.exr")
    g.connect(f"in.{port}", "out.color")
    with tempfile.TemporaryDirectory() as tmp:
        file = pathlib.Path(tmp) / "g.ron"
        g.save(str(file))
        s = lg.Session(str(file), frame=frame, out=tmp)
        return s.render(1)["out"]


def save(name, rgb):
    rgba = np.concatenate([rgb, np.ones(rgb.shape[:2] + (1,), np.float32)], axis=2)
    lg.Image(rgba.astype(np.float32)).save_png(str(OUT / name))
    print("wrote", OUT / name)


def gap(h):
    return np.full((h, 8, 3), 1.0, np.float32)


def beachball():
    seq = IMAGES / "Beachball" / "multipart.####.exr"
    colour = read(seq, frame=1)
    depth = read(seq, "depth", "scalar", frame=1)[:, :, 0]
    motion = read(seq, "forward", "vector", frame=1)
    inside = depth > 0
    d = np.zeros_like(depth)
    lo, hi = np.percentile(depth[inside], [1, 99])
    d[inside] = 1.0 - np.clip((depth[inside] - lo) / (hi - lo), 0, 1) * 0.8
    # The ball moves by about (+42, −40) pixels a frame; shown: each component's spread
    # over the ball (1st to 99th percentile) from dark to bright, u in red, v in green.
    m = np.zeros(depth.shape + (3,), np.float32)
    for c in (0, 1):
        lo, hi = np.percentile(motion[:, :, c][inside], [1, 99])
        m[:, :, c][inside] = 0.15 + 0.85 * np.clip((motion[:, :, c][inside] - lo) / (hi - lo), 0, 1)
    tiles = [srgb(colour[:, :, :3]), np.repeat(d[:, :, None], 3, axis=2), np.clip(m, 0, 1)]
    tiles = [shrink(t, 4) for t in tiles]
    h = tiles[0].shape[0]
    save("compositing_beachball_layers.png", np.concatenate([tiles[0], gap(h), tiles[1], gap(h), tiles[2]], axis=1))


def display_window():
    placed = srgb(read(IMAGES / "DisplayWindow" / "t08.exr")[:, :, :3])
    crop = placed[40:340, 30:430]
    frame = np.full_like(placed, 1.0)
    frame[: crop.shape[0], : crop.shape[1]] = crop
    h = placed.shape[0]
    save("compositing_display_window.png", np.concatenate([placed, gap(h), frame], axis=1))


def chromaticities():
    xyz = read(IMAGES / "Chromaticities" / "XYZ.exr")[:, :, :3]
    rec = read(IMAGES / "Chromaticities" / "Rec709.exr")[:, :, :3]
    m = np.array([[3.2409699, -1.5373832, -0.4986108], [-0.9692436, 1.8759675, 0.0415551], [0.0556301, -0.2039770, 1.0569715]])
    raw = xyz @ np.linalg.inv(m).T  # undo the conversion: the values as stored
    tiles = [shrink(srgb(t), 2) for t in (raw, xyz, rec)]
    h = tiles[0].shape[0]
    save("compositing_chromaticities.png", np.concatenate([tiles[0], gap(h), tiles[1], gap(h), tiles[2]], axis=1))


if __name__ == "__main__":
    beachball()
    display_window()
    chromaticities()
