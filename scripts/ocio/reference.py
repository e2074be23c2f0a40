"""OpenColorIO reference values for lumagraph's colour management.

Writes tests/color/ocio_reference.json: a fixed list of linear RGB pixels run
through PyOpenColorIO's CPU processors for three configs, so that the Rust side
(the pure-Rust `ocio` crate, a port of OpenColorIO 2.5) can be tested against
the C++ library. It also (re)writes the two LUT files of the user config in
tests/color/user_config/ when their generated contents differ from the files.

Not run by CI: the JSON and the LUT files are committed, and the Rust tests
only read them. Rerun it by hand, from the repository root, after changing the
pixels, the configs or the OpenColorIO version:

    python3 -m venv .venv-ocio
    .venv-ocio/bin/pip install opencolorio==2.6.0 numpy
    .venv-ocio/bin/python scripts/ocio/reference.py
    # the OpenEXR project's TestImages (needs `pip install OpenEXR` too):
    .venv-ocio/bin/python scripts/ocio/reference.py --testimages

With --blender it writes tests/color/ocio_blender.json: the same conversions of
the same pixels through Blender 4.2's own config (AgX, Filmic, Khronos PBR
Neutral; the one scripts/setup.sh unpacks from the bpy 4.2.0 wheel, or
$LUMAGRAPH_BLENDER_OCIO).

With --testimages it writes tests/color/ocio_testimages.json instead: the same
conversions, for the CG config only, of pixels sampled from every colour file of
the OpenEXR project's TestImages (../shared/assets/openexr-images/TestImages, or
$LUMAGRAPH_OPENEXR_IMAGES/TestImages) as OpenEXR's Python bindings read them:
30 fixed-seed random pixels per file and its darkest and brightest, finite
pixels only; "samples" names each pixel's file and position.

(PyOpenColorIO 2.6.0, the wheel on PyPI, was used to write the committed JSON;
its built-in configs cg-config-v4.0.0_aces-v2.0_ocio-v2.5 and
studio-config-v4.0.0_aces-v2.0_ocio-v2.5 serialize identically to the copies
in the `ocio` 0.3.0 crate. Python 3.11.) The output is deterministic: a rerun
with the same versions gives the same bytes.

What is computed, per config:
  * working_space: the scene-linear Rec.709 space ("Linear Rec.709 (sRGB)" in
    the ACES built-in configs, "Linear Rec.709" in the user config).
  * to_working[space]: the pixels taken as values in `space`, converted with
    config.getProcessor(space, working).getDefaultCPUProcessor().
    from_working[space]: the pixels taken as working-space values, converted
    with config.getProcessor(working, space). Every colour space of the config
    is included, active AND inactive (getColorSpaceNames(SEARCH_REFERENCE_SPACE_ALL,
    COLORSPACE_ALL), in config order), both scene- and display-referred; the
    inactive ones are also listed under "inactive_color_spaces". Aliases, roles
    and named transforms are not included.
  * displays[display][view]: the pixels taken as working-space values, through
    config.getProcessor(working, display, view, TRANSFORM_DIR_FORWARD), i.e. a
    DisplayViewTransform(src=working, display, view) in the forward direction.
    Every display (getDisplaysAll(); active ones first, in active order) and
    every view of it (display-defined and shared, in getViews(display) order,
    then any inactive ones), looks included as the view defines them.
  * default_display / default_view: config.getDefaultDisplay() and
    config.getDefaultView(default_display).
Where PyOpenColorIO raises, the entry is {"error": "<message>"}.

Numbers: each float32 result is written with 8 significant digits; NaN and
infinities are written as the strings "nan", "inf", "-inf". The input pixels
are short decimals (at most 6 significant digits); the values processed are
their nearest float32 (parse as f64, cast to f32 in Rust).

The user config's LUTs (documented in tests/color/user_config/config.ocio):
  log_to_lin.spi1d: 1024 entries over [0, 1],
      lin(x) = 0.18 * (2^(16 * (x - 0.6)) - 2^-9.6)      (lin(0) = 0, lin(0.6) ~ 0.18, lin(1) ~ 15.2)
  film_look.cube: 9^3 entries over [0, 1]^3, input in Log code values,
      l = lin(rgb) per channel, Y = 0.2126 l.r + 0.7152 l.g + 0.0722 l.b,
      c = Y + 0.8 (l - Y)  (20 % desaturation),  out = c / (1 + c)  (display linear).
"""

from __future__ import annotations

import json
import math
import os
import random
import sys
from pathlib import Path

# OCIO reads these at config load time; they would change which spaces,
# displays and views are active, so clear them for a reproducible result.
for _var in ("OCIO", "OCIO_ACTIVE_DISPLAYS", "OCIO_ACTIVE_VIEWS",
             "OCIO_INACTIVE_COLORSPACES", "OCIO_OPTIMIZATION_FLAGS", "OCIO_USER_CATEGORIES"):
    os.environ.pop(_var, None)

import numpy as np  # noqa: E402
import PyOpenColorIO as OCIO  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
OUT_JSON = REPO / "tests" / "color" / "ocio_reference.json"
USER_DIR = REPO / "tests" / "color" / "user_config"
USER_CONFIG = USER_DIR / "config.ocio"

CONFIGS = [
    # (key in the JSON, how to load it, working space)
    ("ocio://cg-config-v4.0.0_aces-v2.0_ocio-v2.5", "ocio://cg-config-v4.0.0_aces-v2.0_ocio-v2.5",
     "Linear Rec.709 (sRGB)"),
    ("ocio://studio-config-v4.0.0_aces-v2.0_ocio-v2.5",
     "ocio://studio-config-v4.0.0_aces-v2.0_ocio-v2.5", "Linear Rec.709 (sRGB)"),
    ("tests/color/user_config/config.ocio", str(USER_CONFIG), "Linear Rec.709"),
]

SEED = 20250611


# --------------------------------------------------------------------------
# Pixels

def make_pixels() -> list[list[float]]:
    px: list[list[float]] = []
    # 16 greys.
    for g in (-1.0, -0.01, 0.0, 1e-4, 0.001, 0.01, 0.05, 0.18, 0.5, 1.0, 2.0, 4.0, 16.0,
              100.0, 1000.0, 1e4):
        px.append([g, g, g])
    # Primaries, secondaries and their desaturated versions (25 % grey mixed
    # in: 1 -> 1, 0 -> 0.25) at 5 levels: 60.
    hues = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 1, 1), (1, 0, 1), (1, 1, 0)]
    for level in (0.01, 0.18, 1.0, 16.0, 1000.0):
        for h in hues:
            px.append([level * c for c in h])
        for h in hues:
            px.append([level * (0.75 * c + 0.25) for c in h])
    # A few hand-picked colours: skin, sky, foliage, near-white, out of gamut.
    px += [
        [0.45, 0.3, 0.2], [0.2, 0.35, 0.6], [0.08, 0.15, 0.04], [0.9, 0.95, 1.05],
        [0.18, 0.18, 0.19], [2.5, 1.2, 0.3], [0.02, 0.01, 0.3], [-0.05, 0.1, 0.2],
        [0.5, -0.02, 0.4], [8.0, 0.5, -0.1], [0.001, 0.002, 0.0005], [0.3, 0.3, 1e-4],
        [60.0, 40.0, 20.0], [0.7, 0.0, 0.35],
    ]
    # 60 fixed-seed random triples: a per-triple magnitude log-uniform over
    # [1e-4, 1e4], each component log-uniform over the two decades below it
    # (kept >= 1e-4); every 5th triple has one component replaced by a
    # negative value log-uniform over [-1, -1e-4] (so all pixels lie in
    # [-1, 1e4]). Python's
    # random.random() sequence is stable across Python versions for a seed.
    rng = random.Random(SEED)
    for i in range(60):
        top = -4.0 + 8.0 * rng.random()
        lo = max(-4.0, top - 2.0)
        trip = [10.0 ** (lo + (top - lo) * rng.random()) for _ in range(3)]
        if i % 5 == 4:  # negative component, log-uniform over [-1, -1e-4]
            trip[i // 5 % 3] = -(10.0 ** (-4.0 * rng.random()))
        px.append([float(f"{v:.6g}") for v in trip])
    # Short decimals: parsing one as f64 and casting to f32 (Rust) gives the
    # same float32 as np.float32 here.
    return [[float(f"{v:.6g}") for v in p] for p in px]


# --------------------------------------------------------------------------
# User config LUTs

def lut_lin(x: float) -> float:
    return 0.18 * (2.0 ** (16.0 * (x - 0.6)) - 2.0 ** -9.6)


def spi1d_text(n: int = 1024) -> str:
    lines = ["Version 1", "From 0.0 1.0", f"Length {n}", "Components 1", "{"]
    lines += [f"    {lut_lin(i / (n - 1)):.8g}" for i in range(n)]
    lines.append("}")
    return "\n".join(lines) + "\n"


def film_look(r: float, g: float, b: float) -> list[float]:
    lr, lg, lb = lut_lin(r), lut_lin(g), lut_lin(b)
    y = 0.2126 * lr + 0.7152 * lg + 0.0722 * lb
    out = []
    for l in (lr, lg, lb):
        c = max(0.0, y + 0.8 * (l - y))
        out.append(c / (1.0 + c))
    return out


def cube_text(n: int = 9) -> str:
    lines = ["# Generated by scripts/ocio/reference.py: Log code values -> 20 % desaturation,",
             "# Reinhard tone curve -> display linear. Test LUT of tests/color/user_config.",
             'TITLE "lumagraph test film look"', f"LUT_3D_SIZE {n}",
             "DOMAIN_MIN 0.0 0.0 0.0", "DOMAIN_MAX 1.0 1.0 1.0"]
    for b in range(n):  # red varies fastest
        for g in range(n):
            for r in range(n):
                v = film_look(r / (n - 1), g / (n - 1), b / (n - 1))
                lines.append(" ".join(f"{x:.6f}" for x in v))
    return "\n".join(lines) + "\n"


def write_if_changed(path: Path, text: str) -> None:
    if path.exists() and path.read_text() == text:
        return
    path.write_text(text)
    print(f"wrote {path.relative_to(REPO)}")


# --------------------------------------------------------------------------
# Evaluation

def fmt(v: float):
    if math.isnan(v):
        return "nan"
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    return float(f"{v:.8g}")


def run(processor, pixels: np.ndarray):
    cpu = processor.getDefaultCPUProcessor()
    buf = np.ascontiguousarray(pixels, dtype=np.float32).copy()
    cpu.applyRGB(buf)
    return [[fmt(float(c)) for c in row] for row in buf]


def guarded(fn, pixels, errors: list, what: str):
    try:
        return run(fn(), pixels)
    except Exception as e:  # PyOpenColorIO raises OCIO.Exception (a RuntimeError)
        errors.append(f"{what}: {e}")
        return {"error": str(e)}


def ordered_displays(config) -> list[str]:
    names = list(config.getDisplays())
    names += [d for d in config.getDisplaysAll() if d not in names]
    return names


def ordered_views(config, display: str) -> list[str]:
    names = list(config.getViews(display))
    for t in (OCIO.VIEW_DISPLAY_DEFINED, OCIO.VIEW_SHARED):
        names += [v for v in config.getViews(t, display) if v not in names]
    return names


def evaluate(key: str, source: str, working: str, pixels: np.ndarray) -> dict:
    config = OCIO.Config.CreateFromFile(source)
    if config.getColorSpace(working) is None:
        sys.exit(f"{key}: no working space {working!r}")
    errors: list[str] = []
    spaces = list(config.getColorSpaceNames(OCIO.SEARCH_REFERENCE_SPACE_ALL, OCIO.COLORSPACE_ALL))
    inactive = list(config.getColorSpaceNames(OCIO.SEARCH_REFERENCE_SPACE_ALL,
                                              OCIO.COLORSPACE_INACTIVE))
    to_working, from_working = {}, {}
    for cs in spaces:
        to_working[cs] = guarded(lambda: config.getProcessor(cs, working), pixels, errors,
                                 f"to_working {cs}")
        from_working[cs] = guarded(lambda: config.getProcessor(working, cs), pixels, errors,
                                   f"from_working {cs}")
    displays: dict = {}
    n_views = 0
    for d in ordered_displays(config):
        displays[d] = {}
        for v in ordered_views(config, d):
            def proc(d=d, v=v):
                # Builds a DisplayViewTransform(src=working, display=d, view=v)
                # and its processor in the forward direction.
                return config.getProcessor(working, d, v, OCIO.TRANSFORM_DIR_FORWARD)
            displays[d][v] = guarded(proc, pixels, errors, f"display {d} / {v}")
            n_views += 1
    default_display = config.getDefaultDisplay()
    print(f"{key}\n  working space {working!r}; {len(spaces)} colour spaces "
          f"({len(inactive)} inactive), {len(displays)} displays, {n_views} views, "
          f"{len(errors)} errors; default {default_display!r} / "
          f"{config.getDefaultView(default_display)!r}")
    for e in errors:
        print(f"    error: {e}")
    return {
        "working_space": working,
        "inactive_color_spaces": inactive,
        "to_working": to_working,
        "from_working": from_working,
        "displays": displays,
        "default_display": default_display,
        "default_view": config.getDefaultView(default_display),
    }


def dump(doc: dict) -> str:
    """JSON with one line per pixel list (colour space / view)."""
    def compact(x):
        return json.dumps(x, separators=(",", ":"), ensure_ascii=False)

    out = ["{"]
    out.append(f'  "generator": {compact(doc["generator"])},')
    out.append(f'  "opencolorio": {compact(doc["opencolorio"])},')
    out.append(f'  "pixels": {compact(doc["pixels"])},')
    out.append('  "configs": {')
    cfg_items = list(doc["configs"].items())
    for ci, (key, cfg) in enumerate(cfg_items):
        out.append(f"    {compact(key)}: {{")
        lines = []
        lines.append(f'      "working_space": {compact(cfg["working_space"])}')
        lines.append(f'      "inactive_color_spaces": {compact(cfg["inactive_color_spaces"])}')
        for section in ("to_working", "from_working"):
            body = ",\n".join(f"        {compact(k)}: {compact(v)}"
                              for k, v in cfg[section].items())
            lines.append(f'      "{section}": {{\n{body}\n      }}')
        disp = []
        for d, views in cfg["displays"].items():
            body = ",\n".join(f"          {compact(v)}: {compact(r)}" for v, r in views.items())
            disp.append(f"        {compact(d)}: {{\n{body}\n        }}")
        lines.append('      "displays": {\n' + ",\n".join(disp) + "\n      }")
        lines.append(f'      "default_display": {compact(cfg["default_display"])}')
        lines.append(f'      "default_view": {compact(cfg["default_view"])}')
        out.append(",\n".join(lines))
        out.append("    }" + ("," if ci + 1 < len(cfg_items) else ""))
    out.append("  }")
    out.append("}")
    return "\n".join(out) + "\n"


# --------------------------------------------------------------------------
# Samples of the OpenEXR project's TestImages

TESTIMAGES_JSON = REPO / "tests" / "color" / "ocio_testimages.json"
SAMPLES_PER_FILE = 30


def testimages_dir() -> Path:
    env = os.environ.get("LUMAGRAPH_OPENEXR_IMAGES")
    root = Path(env) if env else REPO.parent / "shared" / "assets" / "openexr-images"
    return root / "TestImages"


def sample_testimages() -> tuple[list[list[float]], list[list]]:
    """Pixels of every colour (RGB or Y) file of TestImages, as OpenEXR reads them: per
    file, SAMPLES_PER_FILE fixed-seed random positions and the darkest and brightest pixel
    (by the mean of R, G, B); non-finite pixels are left out (OpenColorIO's CPU and GPU
    paths differ on NaN and infinities). Returns the pixels and [file, x, y] per pixel."""
    import OpenEXR

    pixels: list[list[float]] = []
    where: list[list] = []
    rng = np.random.default_rng(SEED)
    for path in sorted(testimages_dir().glob("*.exr")):
        with OpenEXR.File(str(path), separate_channels=True) as f:
            channels = f.channels()
            if all(c in channels for c in "RGB"):
                rgb = np.stack([channels[c].pixels.astype(np.float32) for c in "RGB"], axis=-1)
            elif list(channels) == ["Y"]:
                y = channels["Y"].pixels.astype(np.float32)
                rgb = np.stack([y, y, y], axis=-1)
            else:
                print(f"  {path.name}: channels {sorted(channels)}: not colour, skipped")
                continue
        h, w, _ = rgb.shape
        finite = np.isfinite(rgb).all(axis=-1)
        mean = np.where(finite, rgb.astype(np.float64).mean(axis=-1), np.nan)
        picks = [np.unravel_index(np.nanargmin(mean), mean.shape),
                 np.unravel_index(np.nanargmax(mean), mean.shape)]
        while len(picks) < SAMPLES_PER_FILE + 2:
            yx = (int(rng.integers(h)), int(rng.integers(w)))
            if finite[yx]:
                picks.append(yx)
        for (py, px) in picks:
            pixels.append([float(f"{float(v):.9g}") for v in rgb[py, px]])
            where.append([path.name, int(px), int(py)])
        print(f"  {path.name}: {w}x{h}, {len(picks)} pixels")
    return pixels, where


def write_testimages() -> None:
    pixels, where = sample_testimages()
    key, source, working = CONFIGS[0]
    doc = {
        "generator": "scripts/ocio/reference.py --testimages",
        "opencolorio": OCIO.__version__,
        "pixels": pixels,
        "configs": {key: evaluate(key, source, working, np.array(pixels, dtype=np.float32))},
    }
    text = dump(doc)
    text = text.replace('  "pixels":', f'  "samples": {json.dumps(where, separators=(",", ":"))},\n  "pixels":', 1)
    json.loads(text)
    TESTIMAGES_JSON.write_text(text)
    print(f"wrote {TESTIMAGES_JSON.relative_to(REPO)} ({len(text.encode())} bytes)")


BLENDER_JSON = REPO / "tests" / "color" / "ocio_blender.json"


def blender_config() -> Path:
    env = os.environ.get("LUMAGRAPH_BLENDER_OCIO")
    if env:
        return Path(env)
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "lumagraph" / "blender-ocio" / "4.2" / "config.ocio"


def write_blender() -> None:
    config = blender_config()
    if not config.is_file():
        sys.exit(f"no Blender config at {config}: run scripts/setup.sh")
    pixels = make_pixels()
    doc = {
        "generator": "scripts/ocio/reference.py --blender",
        "opencolorio": OCIO.__version__,
        "pixels": pixels,
        "configs": {"blender": evaluate("blender (Blender 4.2's config)", str(config),
                                        "Linear Rec.709",
                                        np.array(pixels, dtype=np.float32))},
    }
    text = dump(doc)
    json.loads(text)
    BLENDER_JSON.write_text(text)
    print(f"wrote {BLENDER_JSON.relative_to(REPO)} ({len(text.encode())} bytes)")


def main() -> None:
    if "--testimages" in sys.argv[1:]:
        OCIO.ClearAllCaches()
        write_testimages()
        return
    if "--blender" in sys.argv[1:]:
        OCIO.ClearAllCaches()
        write_blender()
        return
    USER_DIR.mkdir(parents=True, exist_ok=True)
    write_if_changed(USER_DIR / "log_to_lin.spi1d", spi1d_text())
    write_if_changed(USER_DIR / "film_look.cube", cube_text())
    OCIO.ClearAllCaches()

    pixels = make_pixels()
    arr = np.array(pixels, dtype=np.float32)
    doc = {
        "generator": "scripts/ocio/reference.py",
        "opencolorio": OCIO.__version__,
        "pixels": pixels,
        "configs": {},
    }
    print(f"PyOpenColorIO {OCIO.__version__}, {len(pixels)} pixels")
    for key, source, working in CONFIGS:
        doc["configs"][key] = evaluate(key, source, working, arr)
    text = dump(doc)
    json.loads(text)  # well-formed
    OUT_JSON.parent.mkdir(parents=True, exist_ok=True)
    OUT_JSON.write_text(text)
    print(f"wrote {OUT_JSON.relative_to(REPO)} ({len(text.encode())} bytes)")


if __name__ == "__main__":
    main()
