#!/usr/bin/env python3
"""Write an OpenEXR-made reference for the EXR reader in crates/footage.

What it does
    Reads every ``*.exr`` under a root folder (by default the OpenEXR project's sample
    images at ``../shared/assets/openexr-images``, relative to the repository root) with
    OpenEXR's OWN readers and writes ``tests/exr/openexr_reference.json``: per file, per
    part, the header facts a reader must get right and a SHA-256 of every channel's
    samples, plus decoded RGBA for luminance/chroma files and a Rec. 709 conversion for
    files with other primaries. The ``Damaged/`` folder (fuzzer-damaged files) is only
    listed, never read.

    Which reader gives what:
      * OpenEXR's Python bindings (``pip install OpenEXR``, 3.4 or later:
        ``OpenEXR.File(path, separate_channels=True)``, which reads through
        Imf::MultiPartInputFile/InputPart): part names, views, types, windows,
        compression, chromaticities, channel list, and the channel samples that are hashed.
      * OpenEXR's C++ library (libOpenEXR from the system, e.g. Debian's libopenexr-dev),
        through ``scripts/exr/rgba_reference.cpp``, which this script compiles with g++
        into a temporary folder on every run:
          - ``rgba``: Imf::RgbaInputFile's output (chroma reconstruction, luminance
            weights from the chromaticities), which the bindings do not offer;
          - ``to_rec709.matrix``: Imf::RGBtoXYZ(file, 1) * Imf::XYZtoRGB(Rec. 709, 1),
            transposed to act on column vectors;
          - a cross-check: the same channels re-read at level 0 with Imf::InputPart /
            Imf::TiledInputPart and hashed again; any difference is reported (and the
            run exits 1). Where the bindings cannot give a part or a channel, the C++
            read is used for its hashes.

JSON written (one file entry per line; keys in this order)::

    {"generator": "scripts/exr/reference.py", "reader": "...", "damaged": [...],
     "files": {"<relative path>": {
        "parts": [{"index", "name", "view", "type", "data_window", "display_window",
                   "chromaticities", "compression",
                   "channels": [{"name", "type", "sampling", "sha256"}]}],
        "rgba": null | {"samples": [[x, y, r, g, b, a], ...]},
        "to_rec709": null | {"matrix": [m00..m22], "samples": [[x, y, r, g, b], ...]}}}}

    * windows are [xmin, ymin, xmax, ymax]; chromaticities [rx, ry, gx, gy, bx, by, wx, wy]
      (float32 values written as the shortest decimal that reads back as the same float32)
      or null without the attribute;
    * sha256: channel samples at resolution level 0 over the part's data window,
      row-major (y outer, x inner); for a subsampled channel only the positions with
      x % xs == 0 and y % ys == 0 (absolute coordinates); each sample little-endian in
      its stored type (half: 16 bits, float: 32 bits, uint: u32). null for deep parts;
    * rgba: only for files whose first part has a ``Y`` channel (what RgbaInputFile reads);
      each value is the half RgbaInputFile returns, written as the shortest decimal that
      reads back as that half (parse as f32 or f64, round to nearest half: compare with
      half::f16::from_f32(v) == decoded, not as f32 values);
    * to_rec709: only for a part whose chromaticities differ from Rec. 709 (OpenEXR's
      default Chromaticities(), compared with its operator!=). The matrix entries are the
      float32 values OpenEXR computes (Imath M44f), shortest float32 decimals, row-major,
      for column vectors (rgb709 = M . rgb_file). Samples are the file's R, G, B channels
      (or, for a luminance/chroma file, RgbaInputFile's R, G, B) multiplied by those
      entries in float64, written with 7 significant digits.
    * sample positions: 2048 distinct pixels of the data window (every pixel if it has
      fewer), chosen with splitmix64 seeded with SEED below and Floyd's algorithm, then
      sorted by (y, x); coordinates are absolute. Files with the same data window get the
      same positions (so Chromaticities/XYZ.exr and Rec709.exr can be compared).
    * a non-finite value would be written as the string "nan", "inf" or "-inf".
    * a file OpenEXR itself refuses gets "error": "<message>" and an empty "parts".

Set-up (once; nothing here installs anything itself):

    python3 -m venv .venv-exr && .venv-exr/bin/pip install OpenEXR numpy
    apt-get update && apt-get install -y g++ pkg-config libopenexr-dev

Run (from the repository root; the same JSON on every run with the same libraries):

    .venv-exr/bin/python scripts/exr/reference.py [--root DIR] [--out FILE]

This is a developer tool for producing test data. It is NOT run by CI.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

SETUP = ("python3 -m venv .venv-exr && .venv-exr/bin/pip install OpenEXR numpy; "
         "apt-get install -y g++ pkg-config libopenexr-dev")

try:
    import numpy as np
    import OpenEXR
except ImportError as exc:  # pragma: no cover - set-up problem
    sys.exit(f"reference.py: {exc}; set up with: {SETUP}")

GENERATOR = "scripts/exr/reference.py"
SEED = 0x4F70656E455852  # "OpenEXR"
NSAMPLES = 2048
REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent

COMPRESSION = {
    "NO_COMPRESSION": "none", "RLE_COMPRESSION": "rle", "ZIPS_COMPRESSION": "zips",
    "ZIP_COMPRESSION": "zip", "PIZ_COMPRESSION": "piz", "PXR24_COMPRESSION": "pxr24",
    "B44_COMPRESSION": "b44", "B44A_COMPRESSION": "b44a", "DWAA_COMPRESSION": "dwaa",
    "DWAB_COMPRESSION": "dwab",
}
PIXEL = {"HALF": ("half", "<f2", 2), "FLOAT": ("float", "<f4", 4), "UINT": ("uint", "<u4", 4)}
STORAGE = ("scanlineimage", "tiledimage", "deepscanline", "deeptile")
STATS: Counter = Counter()


# ---------------------------------------------------------------- JSON with exact numbers

class Num(str):
    """A number already formatted; written verbatim."""


def num_f64(v: float, digits: int | None = None) -> object:
    v = float(v)
    if math.isnan(v):
        return "nan"
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    if v == 0 and math.copysign(1.0, v) < 0:
        return Num("-0.0")
    if v == int(v) and abs(v) < 2**53:
        return Num(str(int(v)))
    return Num(f"{v:.{digits}g}" if digits else repr(v))


def num_half(h) -> object:
    """Shortest decimal that reads back (as f32 or f64, then rounded to nearest half) as
    the same half; checked for all 63488 finite halves in self_test()."""
    h = np.float16(h)
    if not np.isfinite(h):
        return num_f64(float(h))
    if h == 0 and np.signbit(h):
        return Num("-0.0")
    if float(h) == int(h):
        return Num(str(int(h)))
    return Num(str(h))


def num_f32(v) -> object:
    """Shortest decimal that reads back as the same float32."""
    f = np.float32(v)
    if not np.isfinite(f):
        return num_f64(float(f))
    if float(f) == int(f) and abs(float(f)) < 2**24:
        return Num(str(int(f)))
    return Num(str(f))


def dumps(o) -> str:
    if isinstance(o, Num):
        return str(o)
    if o is None:
        return "null"
    if o is True:
        return "true"
    if o is False:
        return "false"
    if isinstance(o, int):
        return str(o)
    if isinstance(o, str):
        return json.dumps(o, ensure_ascii=False)
    if isinstance(o, (list, tuple)):
        return "[" + ",".join(dumps(x) for x in o) + "]"
    if isinstance(o, dict):
        return "{" + ",".join(dumps(str(k)) + ":" + dumps(v) for k, v in o.items()) + "}"
    raise TypeError(type(o))


def self_test() -> None:
    """Checks the number formats and the matrix convention helpers before a run."""
    h = np.arange(65536, dtype=np.uint16).view(np.float16)
    h = h[np.isfinite(h)]
    back = np.array([float(str(num_half(v))) for v in h])
    assert (back.astype(np.float16).view(np.uint16) == h.view(np.uint16)).all(), "half via f64"
    assert (back.astype(np.float32).astype(np.float16).view(np.uint16) == h.view(np.uint16)).all(), "half via f32"
    for v in (0.64, 0.33, 1 / 3, 0.3127, 1e-9, 65504.0):
        assert np.float32(float(str(num_f32(v)))) == np.float32(v), v


def write_json(path: Path, reader: str, damaged: list[str], files: dict) -> None:
    lines = ["{",
             f'"generator":{dumps(GENERATOR)},',
             f'"reader":{dumps(reader)},',
             f'"damaged":{dumps(damaged)},',
             '"files":{']
    items = list(files.items())
    for i, (k, v) in enumerate(items):
        lines.append(dumps(k) + ":" + dumps(v) + ("," if i + 1 < len(items) else ""))
    lines += ["}", "}"]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


# ---------------------------------------------------------------- sample positions

def splitmix64(state: int):
    while True:
        state = (state + 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF
        z = state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
        yield z ^ (z >> 31)


def positions(dw: list[int]) -> list[tuple[int, int]]:
    """NSAMPLES distinct absolute (x, y) in the data window, sorted by (y, x)."""
    xmin, ymin, xmax, ymax = dw
    w, h = xmax - xmin + 1, ymax - ymin + 1
    total = w * h
    if total <= NSAMPLES:
        chosen = range(total)
    else:
        rng = splitmix64(SEED)
        s: set[int] = set()
        for j in range(total - NSAMPLES, total):  # Floyd's algorithm
            t = next(rng) % (j + 1)
            s.add(j if t in s else t)
        chosen = sorted(s)
    return [(xmin + i % w, ymin + i // w) for i in chosen]


# ---------------------------------------------------------------- C++ helper

class Cxx:
    def __init__(self, tmp: Path):
        src = HERE / "rgba_reference.cpp"
        exe = tmp / "rgba_reference"
        cxx = os.environ.get("CXX", "g++")
        try:
            flags = subprocess.run(["pkg-config", "--cflags", "--libs", "OpenEXR"], check=True,
                                   capture_output=True, text=True).stdout.split()
        except (OSError, subprocess.CalledProcessError) as exc:
            sys.exit(f"reference.py: pkg-config OpenEXR failed ({exc}); set up with: {SETUP}")
        r = subprocess.run([cxx, "-std=c++17", "-O2", str(src), "-o", str(exe), *flags],
                           capture_output=True, text=True)
        if r.returncode:
            sys.exit(f"reference.py: compiling {src.name} failed:\n{r.stderr}")
        self.exe = exe
        self.version = self.run("version")[0].split()[1]
        st = self.run("selftest")
        if st != ["selftest ok"]:
            sys.exit(f"reference.py: C++ matrix self-test failed: {st}")

    def run(self, *args: str) -> list[str]:
        r = subprocess.run([str(self.exe), *args], capture_output=True, text=True)
        lines = r.stdout.splitlines()
        if r.returncode:
            msg = next((l[6:] for l in lines if l.startswith("error ")), r.stderr.strip())
            raise RuntimeError(msg or f"exit {r.returncode}")
        return lines


def cxx_version_label(version: str) -> str:
    try:
        deb = subprocess.run(["dpkg-query", "-W", "-f", "${Version}", "libopenexr-dev"],
                             capture_output=True, text=True)
        if deb.returncode == 0 and deb.stdout.strip():
            return f"libOpenEXR {version} (Debian {deb.stdout.strip()})"
    except OSError:
        pass
    return f"libOpenEXR {version}"


# ---------------------------------------------------------------- per file

def enum_name(v) -> str:
    return str(v).split(".")[-1]


def window(box) -> list[int]:
    lo, hi = box
    return [int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1])]


def sampled_extent(lo: int, hi: int, s: int) -> int:
    first = -((-lo) // s)  # ceil(lo / s)
    last = hi // s
    return max(0, last - first + 1)


def sha_of_array(arr, dtype: str) -> str:
    return hashlib.sha256(np.ascontiguousarray(arr).astype(dtype, copy=False).tobytes()).hexdigest()


def process(path: Path, rel: str, cxx: Cxx, tmp: Path, cross_check: bool, notes: list[str]) -> dict:
    entry: dict = {"parts": [], "rgba": None, "to_rec709": None}
    try:
        headers = OpenEXR.File(str(path), header_only=True).parts
    except Exception as exc:  # OpenEXR refuses the file
        entry["error"] = str(exc)
        notes.append(f"{rel}: OpenEXR (Python) refuses the file: {exc}")
        return entry
    try:
        full = {p.part_index: p for p in OpenEXR.File(str(path), separate_channels=True).parts}
    except Exception as exc:
        full = {}
        notes.append(f"{rel}: Python bindings could not read pixels: {exc}")

    # C++: chromaticities + matrices, and the independent level-0 read.
    chroma = {}
    cxx_channels: dict[tuple[int, str], tuple[str, int, int]] = {}
    for line in cxx.run("header", str(path)):
        f = line.split()
        if f[0] == "chroma" and f[2] != "none":
            chroma[int(f[1])] = (f[2] == "1", [float(x) for x in f[3:11]], [float(x) for x in f[11:20]])
        elif f[0] == "channel":
            f = line.split(" ", 6)
            cxx_channels[(int(f[1]), f[6])] = (f[3], int(f[4]), int(f[5]))
    cxx_sha: dict[tuple[int, str], str] = {}
    if cross_check or len(full) < len(headers):
        d = tmp / "dump"
        shutil.rmtree(d, ignore_errors=True)
        d.mkdir()
        try:
            for line in cxx.run("dump", str(path), str(d)):
                f = line.split(" ", 6)
                if f[0] == "dump":
                    data = (d / f"{f[1]}_{f[2]}.bin").read_bytes()
                    cxx_sha[(int(f[1]), f[6])] = hashlib.sha256(data).hexdigest()
        except RuntimeError as exc:
            notes.append(f"{rel}: C++ InputPart read failed: {exc}")
        shutil.rmtree(d, ignore_errors=True)

    rgb_source: dict[int, dict] = {}
    for hp in headers:
        idx = hp.part_index
        h = hp.header
        ptype = enum_name(hp.type())
        if ptype not in STORAGE:
            raise RuntimeError(f"{rel}: unknown part type {ptype}")
        deep = ptype.startswith("deep")
        dw = window(h["dataWindow"])
        chrom = h.get("chromaticities")
        part = {
            "index": idx,
            "name": h.get("name"),
            "view": h.get("view"),
            "type": ptype,
            "data_window": dw,
            "display_window": window(h["displayWindow"]),
            "chromaticities": None if chrom is None else [num_f32(c) for c in chrom],
            "compression": COMPRESSION[enum_name(h["compression"])],
            "channels": [],
        }
        if chrom is not None and idx in chroma:
            if any(np.float32(a) != np.float32(b) for a, b in zip(chrom, chroma[idx][1])):
                notes.append(f"{rel} part {idx}: chromaticities differ between Python and C++")
        fp = full.get(idx)
        for ch in sorted(h["channels"], key=lambda c: c.name.encode()):
            # The header-only channel list carries no pixel type: take it from the read
            # channel, else from the C++ header listing.
            xs, ys = int(ch.xSampling), int(ch.ySampling)
            read = fp.channels.get(ch.name) if fp is not None else None
            cinfo = cxx_channels.get((idx, ch.name))
            if read is not None:
                tname = PIXEL[enum_name(read.type())][0]
            elif cinfo is not None:
                tname = cinfo[0]
            else:
                raise RuntimeError(f"{rel} part {idx} channel {ch.name}: no pixel type")
            if cinfo is not None and cinfo != (tname, xs, ys):
                notes.append(f"{rel} part {idx} channel {ch.name}: MISMATCH Python {(tname, xs, ys)} vs C++ {cinfo}")
            dtype = {v[0]: v[1] for v in PIXEL.values()}[tname]
            sha = None
            if not deep:
                nx, ny = sampled_extent(dw[0], dw[2], xs), sampled_extent(dw[1], dw[3], ys)
                arr = read.pixels if read is not None else None
                if arr is not None and tuple(arr.shape) == (ny, nx):
                    sha = sha_of_array(arr, dtype)
                    if xs == 1 and ys == 1:
                        rgb_source.setdefault(idx, {})[ch.name] = arr
                    other = cxx_sha.get((idx, ch.name))
                    if other is not None and other == sha:
                        STATS["cross_checked"] += 1
                    if cross_check and other is not None and other != sha:
                        notes.append(f"{rel} part {idx} channel {ch.name}: MISMATCH Python {sha[:12]} vs C++ {other[:12]}")
                    elif cross_check and other is None:
                        notes.append(f"{rel} part {idx} channel {ch.name}: no C++ read to cross-check")
                else:
                    got = None if arr is None else tuple(arr.shape)
                    sha = cxx_sha.get((idx, ch.name))
                    notes.append(f"{rel} part {idx} channel {ch.name}: Python gave {got}, expected "
                                 f"{(ny, nx)}; using C++ read" + ("" if sha else " (none: sha256 null)"))
            part["channels"].append({"name": ch.name, "type": tname, "sampling": [xs, ys], "sha256": sha})
        entry["parts"].append(part)

    # RgbaInputFile for luminance files (it reads the first part's default layer).
    rgba_img = None
    p0 = entry["parts"][0] if entry["parts"] else None
    if p0 and any(c["name"] == "Y" for c in p0["channels"]):
        out = tmp / "rgba.bin"
        f = cxx.run("rgba", str(path), str(out))[0].split()
        dw = [int(v) for v in f[1:5]]
        if dw != p0["data_window"]:
            raise RuntimeError(f"{rel}: RgbaInputFile data window {dw} != {p0['data_window']}")
        w, hgt = dw[2] - dw[0] + 1, dw[3] - dw[1] + 1
        rgba_img = np.frombuffer(out.read_bytes(), dtype="<f2").reshape(hgt, w, 4)
        out.unlink()
        samples = []
        for x, y in positions(dw):
            px = rgba_img[y - dw[1], x - dw[0]]
            samples.append([x, y] + [num_half(v) for v in px])
        entry["rgba"] = {"samples": samples}

    # Rec. 709 conversion for the first part with other primaries.
    for part in entry["parts"]:
        idx = part["index"]
        if idx not in chroma or not chroma[idx][0]:
            continue
        m = np.array(chroma[idx][2], dtype=np.float64).reshape(3, 3)
        dw = part["data_window"]
        src = rgb_source.get(idx, {})
        if all(c in src for c in "RGB"):
            def rgb(x, y, src=src, dw=dw):
                return [float(src[c][y - dw[1], x - dw[0]]) for c in "RGB"]
        elif idx == 0 and rgba_img is not None:
            def rgb(x, y, dw=dw):
                return [float(v) for v in rgba_img[y - dw[1], x - dw[0], :3]]
        else:
            notes.append(f"{rel} part {idx}: other primaries but no R,G,B to convert")
            entry["to_rec709"] = {"matrix": [num_f32(v) for v in m.flat], "samples": []}
            break
        samples = []
        for x, y in positions(dw):
            v = m @ np.array(rgb(x, y), dtype=np.float64)
            samples.append([x, y] + [num_f64(c, 7) for c in v])
        entry["to_rec709"] = {"matrix": [num_f32(v) for v in m.flat], "samples": samples}
        if len(entry["parts"]) > 1:
            notes.append(f"{rel}: to_rec709 is for part {idx}")
        break
    return entry


def summary(rel: str, e: dict) -> str:
    if "error" in e:
        return f"{rel}: REFUSED by OpenEXR: {e['error']}"
    types = Counter(p["type"] for p in e["parts"])
    nch = sum(len(p["channels"]) for p in e["parts"])
    nsha = sum(1 for p in e["parts"] for c in p["channels"] if c["sha256"])
    extra = []
    if e["rgba"]:
        extra.append(f"rgba {len(e['rgba']['samples'])}")
    if e["to_rec709"]:
        extra.append(f"to_rec709 {len(e['to_rec709']['samples'])}")
    t = ",".join(f"{k}" + (f"x{v}" if v > 1 else "") for k, v in sorted(types.items()))
    return (f"{rel}: {len(e['parts'])} part(s) [{t}] {nch} channels, {nsha} hashed"
            + (", " + ", ".join(extra) if extra else ""))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", type=Path, default=REPO / ".." / "shared" / "assets" / "openexr-images",
                    help="folder with the OpenEXR sample images (default ../shared/assets/openexr-images)")
    ap.add_argument("--out", type=Path, default=REPO / "tests" / "exr" / "openexr_reference.json",
                    help="JSON to write (default tests/exr/openexr_reference.json)")
    ap.add_argument("--no-cross-check", action="store_true",
                    help="skip re-reading every channel with the C++ library")
    args = ap.parse_args()
    root = args.root.resolve()
    if not root.is_dir():
        sys.exit(f"reference.py: no folder {root}")

    damaged, exrs = [], []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames.sort()
        for name in sorted(filenames):
            rel = (Path(dirpath) / name).relative_to(root).as_posix()
            if rel.split("/")[0] == "Damaged":
                if not name.lower().startswith("readme"):
                    damaged.append(rel)
            elif name.lower().endswith(".exr"):
                exrs.append(rel)
    damaged.sort()
    exrs.sort()

    self_test()
    notes: list[str] = []
    files: dict = {}
    with tempfile.TemporaryDirectory(prefix="exr-reference-") as t:
        tmp = Path(t)
        cxx = Cxx(tmp)
        reader = (f"OpenEXR {OpenEXR.__version__} Python bindings (headers, channel samples); "
                  f"{cxx_version_label(cxx.version)} C++ for RgbaInputFile, chromaticity matrices "
                  f"and a level-0 cross-check")
        for rel in exrs:
            files[rel] = process(root / rel, rel, cxx, tmp, not args.no_cross_check, notes)
            print(summary(rel, files[rel]), flush=True)

    write_json(args.out, reader, damaged, files)

    folders = Counter(rel.split("/")[0] if "/" in rel else "." for rel in exrs)
    parts = [p for e in files.values() for p in e["parts"]]
    print()
    print("reader:", reader)
    print("per folder:", ", ".join(f"{k} {v}" for k, v in sorted(folders.items())), f"| Damaged {len(damaged)} (listed only)")
    print(f"totals: {len(files)} files, {len(parts)} parts "
          f"({sum(1 for p in parts if p['type'].startswith('deep'))} deep), "
          f"{sum(len(p['channels']) for p in parts)} channels "
          f"({sum(1 for p in parts for c in p['channels'] if c['sha256'])} hashed), "
          f"{sum(1 for e in files.values() if e['rgba'])} with rgba, "
          f"{sum(1 for e in files.values() if e['to_rec709'])} with to_rec709, "
          f"{sum(1 for e in files.values() if 'error' in e)} refused; "
          f"{STATS['cross_checked']} channel hashes confirmed by the C++ level-0 read")
    for n in notes:
        print("note:", n)
    print(f"wrote {args.out} ({args.out.stat().st_size} bytes)")
    return 1 if any("MISMATCH" in n for n in notes) else 0


if __name__ == "__main__":
    sys.exit(main())
