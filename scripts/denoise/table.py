#!/usr/bin/env python3
"""The denoise suite's table in docs/denoise.md ("Figures"), from `lumagraph converge` runs.

Reads converge_NAME/converge.csv (the runs of graphs/denoise_inputs.ron that
`suite.py --steps converge` makes, or the loop below) for every suite scene and prints one
Markdown table: per scene, the relMSE at each spp of the raw accumulation, of the a-trous
`Denoise`, of `RegressionDenoise` and of the `OIDN` node; each denoiser's time per frame as
converge measured it (its passes submitted alone on a CPU adapter; OIDN: read back, filter,
upload), fastest and median over the run's checkpoints; and the better lumagraph
denoiser's relMSE over OIDN's. Then how far the OIDN node is from `pyoidn`'s figure on the
same accumulation (baseline.csv).

Usage (from the repository root; the standard library only):
  for s in cornell:assets/cornell.ron:tests/reference/cornell_ref.exr \\
           mesh_env:assets/bench/mesh_env.ron:tests/reference/denoise/mesh_env_ref.exr \\
           boxtextured:tests/scenes/denoise/boxtextured.ron:tests/reference/denoise/boxtextured_ref.exr \\
           metals:tests/scenes/denoise/metals.ron:tests/reference/denoise/metals_ref.exr; do
    IFS=: read -r name scene ref <<< "$s"
    target/release/lumagraph converge graphs/denoise_inputs.ron --scene "$scene" \\
        --reference "$ref" --seconds 60 --out "/tmp/converge_$name"
  done
  python3 scripts/denoise/table.py --converge-out /tmp
"""
import argparse
import csv
import os
import statistics
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCENES = ("cornell", "mesh_env", "boxtextured", "metals")
# column label -> converge output (node id in graphs/denoise_inputs.ron), baseline.csv column
OUTPUTS = {"raw": ("accumulate", "raw_relmse"), "à-trous": ("denoise", "atrous_relmse"),
           "regression": ("regression", "regression_relmse"), "OIDN": ("oidn", "oidn_relmse")}


def sci(v):
    """2.36e-3, as the docs write relMSE."""
    m, e = f"{v:.2e}".split("e")
    return f"{m}e{int(e)}"


def read_converge(path):
    with open(path) as f:
        return {(r["output"], int(r["spp"])): r for r in csv.DictReader(f)}


def read_baseline():
    with open(os.path.join(ROOT, "tests", "reference", "denoise", "baseline.csv")) as f:
        return {(r["scene"], int(r["spp"])): r for r in csv.DictReader(f)}


def table(runs, spps):
    """One row per scene: relMSE at each spp (the lowest denoiser's in bold), each denoiser's
    time per frame (fastest / median over the run's checkpoints: it depends on the
    machine's load, not on the scene or the spp), the better lumagraph denoiser over OIDN
    at the middle spp."""
    at = spps[len(spps) // 2]
    heads = [f"{k} {' / '.join(map(str, spps))}" for k in OUTPUTS]
    lines = ["| scene | " + " | ".join(heads) + " | ms per frame: à-trous, regression, OIDN "
             f"(fastest / median) | best / OIDN at {at} |",
             "|---|" + "---:|" * (len(OUTPUTS) + 2)]
    for name, rows in runs.items():
        rel = {(k, spp): float(rows[(o, spp)]["relmse"])
               for k, (o, _) in OUTPUTS.items() for spp in spps if (o, spp) in rows}
        cells = []
        for k in OUTPUTS:
            vals = []
            for spp in spps:
                if (k, spp) not in rel:
                    vals.append("—")
                    continue
                best = min(rel.get((d, spp), float("inf")) for d in list(OUTPUTS)[1:])
                v = sci(rel[(k, spp)])
                vals.append(f"**{v}**" if k != "raw" and rel[(k, spp)] == best else v)
            cells.append(" / ".join(vals))
        times = []
        for k in list(OUTPUTS)[1:]:
            ms = sorted(float(r["gpu_ms"]) for (o, _), r in rows.items()
                        if o == OUTPUTS[k][0] and r["gpu_ms"])
            times.append(f"{ms[0]:.0f} / {statistics.median(ms):.0f}" if ms else "—")
        cells.append(", ".join(times))
        if all((k, at) in rel for k in ("à-trous", "regression", "OIDN")):
            ours = min(rel[("à-trous", at)], rel[("regression", at)])
            cells.append(f"{ours / rel[('OIDN', at)]:.2f}")
        else:
            cells.append("—")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def against_pyoidn(runs, spps):
    """The OIDN node's relMSE against pyoidn's on the same accumulation, and the raw
    accumulation's against its recorded figure (how far the input itself moved)."""
    base = read_baseline()
    out = []
    for name, rows in runs.items():
        for spp in spps:
            b = base.get((name, spp))
            node, raw = rows.get(("oidn", spp)), rows.get(("accumulate", spp))
            if b is None or node is None or raw is None:
                continue
            d = float(node["relmse"]) / float(b["oidn_relmse"]) - 1
            r = float(raw["relmse"]) / float(b["raw_relmse"]) - 1
            out.append(f"  {name} {spp} spp: OIDN node {float(node['relmse']):.6e}, pyoidn "
                       f"{float(b['oidn_relmse']):.6g} ({d:+.1e}); raw {r:+.1e} from baseline.csv")
    return "\n".join(out)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("names", nargs="*", help="suite scenes (default: all): " + ", ".join(SCENES))
    p.add_argument("--converge-out", default=tempfile.gettempdir(),
                   help="where the converge_NAME folders are")
    p.add_argument("--spp", type=int, nargs="+", default=[4, 16, 64])
    a = p.parse_args()
    runs = {n: read_converge(os.path.join(a.converge_out, "converge_" + n, "converge.csv"))
            for n in a.names or SCENES}
    print(table(runs, a.spp))
    print()
    print("OIDN node against pyoidn (baseline.csv):")
    print(against_pyoidn(runs, a.spp))


if __name__ == "__main__":
    main()
