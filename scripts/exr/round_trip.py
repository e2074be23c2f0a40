#!/usr/bin/env python3
"""Check lumagraph's EXR round trip with OpenEXR's own reader.

What it does
    ``tests/exr_round_trip/`` reads every layer of the OpenEXR sample images through
    ``ImageInput`` and writes it back through ``Output`` and ``MultiLayerOutput``
    (``data_window: source``, ``type: source``). Run with ``LUMAGRAPH_ROUND_TRIP_OUT=DIR``
    it leaves the files it wrote in DIR with a ``manifest.json`` naming, for each, its
    source file and, per part written, the source part, the channels it should hold and
    how it is held to the source. This script re-reads both the written files and their
    sources with OpenEXR's Python bindings (not lumagraph's reader) and compares:

      * part name and view, display window, data window (the source's, or the source's
        cut to the display window where it has overscan), channel names and types;
      * the header attributes the source part holds beside the structural ones
        (``owner``, ``comments``, ``pixelAspectRatio``, ``screenWindowCenter``,
        ``multiView``, custom ones…): each must be written with the same value, except
        those lumagraph says it does not carry (``chromaticities`` other than Rec. 709,
        ``preview``, ``tiles``), which are counted by name;
      * the samples of every channel, bit for bit, for parts whose values are not
        converted ("Identical", and "Cropped": the source cut to the written window).
        Converted colour and luminance/chroma images written as RGB are checked for names,
        types and windows only (the Rust test holds their values to lumagraph's reader).

Usage
    python3 -m venv /tmp/venv-exr && /tmp/venv-exr/bin/pip install OpenEXR numpy
    LUMAGRAPH_ROUND_TRIP_OUT=/tmp/rt cargo test --test exr_round_trip
    /tmp/venv-exr/bin/python scripts/exr/round_trip.py /tmp/rt

Prints one line per problem and a summary; exits 1 if anything differs.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import OpenEXR

# Attributes that describe the file's structure, which the writer decides.
STRUCTURAL = {
    "channels", "chunkCount", "compression", "dataWindow", "displayWindow", "type",
    "name", "view", "version",
}
# Attributes lumagraph names as not carried (and when).
NOT_CARRIED = {"tiles", "preview", "chromaticities"}


def same(a, b):
    """Whether two header values are equal (numpy arrays and tuples of them included)."""
    if isinstance(a, (tuple, list)) and isinstance(b, (tuple, list)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b))
    return a == b


def window(header, key):
    lo, hi = header[key]
    return (int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1]))


def intersect(a, b):
    """The intersection of two windows, or None."""
    w = (max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3]))
    return None if w[0] > w[2] or w[1] > w[3] else w


def bits(pixels):
    return pixels.view({2: np.uint16, 4: np.uint32}[pixels.dtype.itemsize])


def check_part(src_part, out_part, expected, counts, problems, label):
    sh, oh = src_part.header, out_part.header
    for key in ("name", "view"):
        if sh.get(key) != oh.get(key):
            problems.append(f"{label}: {key} {oh.get(key)!r}, the source's {sh.get(key)!r}")
    display = window(sh, "displayWindow")
    if window(oh, "displayWindow") != display:
        problems.append(f"{label}: display window {window(oh, 'displayWindow')}, not {display}")
    data = intersect(window(sh, "dataWindow"), display)
    empty = data is None  # the data window lies outside the display window
    if empty:  # one empty pixel is written
        data = (display[0], display[1], display[0], display[1])
    if window(oh, "dataWindow") != data:
        problems.append(f"{label}: data window {window(oh, 'dataWindow')}, not {data}")
    names = sorted(out_part.channels)
    if names != sorted(expected["channels"]):
        problems.append(f"{label}: channels {names}, not {sorted(expected['channels'])}")
        return
    kind = expected["kind"]
    for name in names:
        out = out_part.channels[name].pixels
        src = src_part.channels.get(name)
        if src is None:  # R G B of a luminance/chroma image: the type of its Y
            src = next(c for n, c in src_part.channels.items() if n.endswith("Y"))
        if out.dtype != src.pixels.dtype:
            problems.append(f"{label}: {name} is {out.dtype}, the source's {src.pixels.dtype}")
            continue
        if kind not in ("Identical", "Cropped"):
            continue
        sx0, sy0 = window(sh, "dataWindow")[:2]
        if empty:
            want = np.zeros_like(out)
        else:
            want = src.pixels[data[1] - sy0:data[3] - sy0 + 1, data[0] - sx0:data[2] - sx0 + 1]
        if not np.array_equal(bits(want), bits(out)):
            problems.append(f"{label}: {name}'s samples differ")
    for key, value in sh.items():
        if key in STRUCTURAL:
            continue
        if key in NOT_CARRIED and key not in oh:
            counts["dropped"][key] = counts["dropped"].get(key, 0) + 1
            continue
        if key == "chromaticities" and not same(value, oh.get(key)):
            # Other primaries: the colour was converted, and Rec. 709 is written.
            counts["dropped"][key] = counts["dropped"].get(key, 0) + 1
            continue
        if key not in oh or not same(value, oh[key]):
            problems.append(f"{label}: attribute {key} {oh.get(key)!r}, the source's {value!r}")
        else:
            counts["carried"] += 1
    counts[kind] = counts.get(kind, 0) + 1


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("written", type=Path, help="LUMAGRAPH_ROUND_TRIP_OUT of the test run")
    parser.add_argument("--root", type=Path, help="the sample images (default: the manifest's)")
    args = parser.parse_args()
    manifest = json.loads((args.written / "manifest.json").read_text())
    root = args.root or Path(manifest["images"])
    counts = {"files": 0, "parts": 0, "carried": 0, "dropped": {}}
    problems = []
    for entry in manifest["files"]:
        label = f"{entry['written']} ({entry['node']} of {entry['source']})"
        src = OpenEXR.File(str(root / entry["source"]), separate_channels=True)
        out = OpenEXR.File(str(args.written / entry["written"]), separate_channels=True)
        counts["files"] += 1
        if len(out.parts) != len(entry["parts"]):
            problems.append(f"{label}: {len(out.parts)} parts, not {len(entry['parts'])}")
            continue
        for i, expected in enumerate(entry["parts"]):
            counts["parts"] += 1
            check_part(src.parts[expected["source_part"]], out.parts[i], expected, counts,
                       problems, f"{label} part {i}")
    for p in problems:
        print(p)
    dropped = ", ".join(f"{k} {v}" for k, v in sorted(counts["dropped"].items()))
    kinds = ", ".join(f"{k} {counts[k]}" for k in ("Identical", "Cropped", "Converted",
                                                    "Reconstructed") if k in counts)
    print(f"OpenEXR {OpenEXR.__version__} re-read {counts['files']} files written by lumagraph "
          f"({counts['parts']} parts: {kinds}); {counts['carried']} source attributes carried "
          f"with the same value; not carried, as noted: {dropped or 'none'}; "
          f"{len(problems)} problems")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
