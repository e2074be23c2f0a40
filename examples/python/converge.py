"""Error against samples from Python: a path tracer and an accumulator built in code, a
reference rendered with another sampler, the relative MSE of the accumulation against it in
NumPy at each sample count, and a plot with matplotlib where it is installed.

    .venv-python/bin/python examples/python/converge.py [--out DIR] [--scene S] [--reference-spp N]

Exits non-zero if the error does not fall as samples are added (CI runs it, through
scripts/python.sh test)."""

import argparse
import pathlib
import sys

import numpy as np

import lumagraph as lg

ROOT = pathlib.Path(__file__).resolve().parents[2]


def graph(sampler):
    g = lg.Graph()
    g.add_node("PathTrace", "pathtrace", samples_per_frame=4, sampler=sampler)
    g.add_node("Accumulate", "accumulate")
    g.add_node("Tonemap", "tonemap", operator="agx")
    g.add_node("Output", "png", path="render.png")
    g.connect("pathtrace.color", "accumulate.color")
    g.connect("accumulate.color", "tonemap.color")
    g.connect("tonemap.color", "png.color")
    return g


def relmse(image, reference):
    a, r = image[..., :3], reference[..., :3]
    return float(np.mean((a - r) ** 2 / (r ** 2 + 1e-2)))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="out/converge-python")
    p.add_argument("--scene", default=str(ROOT / "assets" / "cornell.ron"))
    p.add_argument("--reference-spp", type=int, default=256)
    args = p.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    reference = lg.Session(graph("independent"), args.scene, out=str(out))
    reference.render(args.reference_spp)
    ref = reference.read("accumulate.color")

    s = lg.Session(graph("sobol"), args.scene, out=str(out))
    rows = []
    for spp in [4, 8, 16, 32, 64]:
        s.render(spp)
        rows.append((spp, relmse(s.read("accumulate.color"), ref)))
    print(f"relMSE against {args.reference_spp} spp (another sampler), {args.scene}:")
    for spp, e in rows:
        print(f"  {spp:4d} spp  {e:.4e}")
    np.savetxt(out / "converge.csv", rows, delimiter=",", header="spp,relmse", comments="")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(4, 3))
        ax.loglog(*zip(*rows), marker="o")
        ax.set_xlabel("samples per pixel")
        ax.set_ylabel("relMSE")
        fig.tight_layout()
        fig.savefig(out / "converge.png", dpi=120)
        print(f"wrote {out / 'converge.png'}")
    except ImportError:
        print("matplotlib is not installed: no plot")
    print(f"wrote {out / 'converge.csv'}")
    if not rows[-1][1] < 0.5 * rows[0][1]:
        sys.exit(f"the error did not fall: {rows}")


if __name__ == "__main__":
    main()
