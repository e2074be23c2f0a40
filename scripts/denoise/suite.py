#!/usr/bin/env python3
"""The denoising test suite: references, noisy inputs, OIDN 2.5 baselines, recorded as data.

Scenes (SUITE below; 256 x 256, 20 bounces): the Cornell box, an environment-lit mesh, a
textured glTF under an environment map, rough metals under the map. Everything
goes into tests/reference/denoise/:

  NAME_ref.exr        reference, linear RGB, half float (Cornell: tests/reference/cornell_ref.exr)
  NAME_converge.csv   Mitsuba 3 raw at 1..256 spp (wall seconds) and OIDN 2.5 on Mitsuba's
                      image, the columns of tests/reference/cornell_converge.csv (what
                      `lumagraph converge --compare` reads)
  baseline.csv        per scene and spp (4, 16, 64): relMSE of lumagraph's raw accumulation, of
                      its a-trous Denoise and its RegressionDenoise, of OIDN 2.5 (RT filter, hdr, albedo + normal) on the
                      same accumulation with lumagraph's G-buffer albedo and normal (cleanAux;
                      and with cleanAux off, OIDN's mode for noisy ones), of OIDN on the colour
                      alone, and OIDN's CPU seconds per frame
  suite.json          per scene: scene file, reference file, reference spp, the reference's own
                      error and how it was made; OIDN timings at 256x256 and 1920x1080

Steps (default: all, in this order; each can run alone):
  refs       references: Mitsuba at --spp (scenes that map, see scripts/references/make.py),
             else (textures) a long lumagraph render of the default graph (SUITE's spp, other
             seeds); own error from two independent halves: relMSE(half1, half2) / 4
  mitsuba    NAME_converge.csv (Mitsuba at 1, 2, 4 .. 256 spp, then OIDN on each; FLIP
             columns need flip-evaluator)
  inputs     lumagraph's accumulation (graphs/denoise_inputs.ron: the default graph with the
             accumulation, G-buffer albedo and normal as outputs, and its OIDN node's output,
             so the graph needs the library `bash scripts/setup.sh` fetches) at 4, 16, 64 spp,
             seed 0; pyoidn on them; baseline.csv (the raw and denoised figures are scored here
             and checked against `lumagraph converge` at the same spp by the next step)
  converge   `lumagraph converge` per scene (--seconds, into --converge-out): the plots
             docs/images/denoise_NAME.png, and the check that baseline.csv's raw, a-trous and
             regression figures are converge's, and its pyoidn figure the OIDN node's
             (scripts/denoise/table.py prints the docs' table from the same runs)
  timing     OIDN CPU time per frame at 256x256 and 1920x1080 (median of --runs)

Usage (from the repository root; Mitsuba 3.9.1 and pyoidn 2.5 in a venv):
  python3 -m venv .venv-mitsuba
  .venv-mitsuba/bin/pip install -r scripts/references/requirements.txt pyoidn==2.5.1 flip-evaluator
  python3 scripts/bench/mesh_env.py make assets/bench/blob.obj
  cargo build --release
  .venv-mitsuba/bin/python scripts/denoise/suite.py                      # everything
  .venv-mitsuba/bin/python scripts/denoise/suite.py mesh_env metals --steps inputs converge
  .venv-mitsuba/bin/python scripts/denoise/suite.py --lumagraph path/to/lumagraph --spp 8192

The converge plots in docs/denoise.md come from
  lumagraph converge graphs/denoise_inputs.ron --scene SCENE \
    --reference tests/reference/denoise/NAME_ref.exr --seconds 60 \
    --compare tests/reference/denoise/NAME_converge.csv --out converge_NAME
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts", "references"))
import make as mk  # noqa: E402  (the scene mapping onto Mitsuba, relmse, render)

OUT = os.path.join(ROOT, "tests", "reference", "denoise")
DEFAULT_GRAPH = "graphs/pathtrace_denoise.ron"
INPUTS_GRAPH = "graphs/denoise_inputs.ron"
SPPS = (4, 16, 64)
SEED = 0  # lumagraph's seed for the scored renders (the scenes' own)

# name -> scene file, reference (None: NAME_ref.exr made here), how it is made
SUITE = {
    "cornell": {"scene": "assets/cornell.ron", "reference": "tests/reference/cornell_ref.exr",
                "made_by": "existing"},
    "mesh_env": {"scene": "assets/bench/mesh_env.ron", "made_by": "mitsuba"},
    # 0.29 M paths/s on lavapipe (the textured shader): 4096 spp take about 16 minutes
    "boxtextured": {"scene": "tests/scenes/denoise/boxtextured.ron", "made_by": "lumagraph",
                    "spp": 4096},
    "metals": {"scene": "tests/scenes/denoise/metals.ron", "made_by": "mitsuba"},
}


def rel(path):
    return os.path.relpath(path, ROOT)


def ref_path(name):
    r = SUITE[name].get("reference")
    return os.path.join(ROOT, r) if r else os.path.join(OUT, name + "_ref.exr")


def read_exr(path):
    import mitsuba as mi
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def write_exr(path, img):
    import mitsuba as mi
    bmp = mi.Bitmap(img.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.convert(component_format=mi.Struct.Type.Float16).write(path)


def rmse(x, ref):
    return float(np.sqrt(np.mean((x - ref) ** 2)))


def load_meta():
    p = os.path.join(OUT, "suite.json")
    if os.path.exists(p):
        with open(p) as f:
            return json.load(f)
    return {"scenes": {}}


def save_meta(meta):
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(OUT, "suite.json"), "w") as f:
        json.dump(meta, f, indent=1)
        f.write("\n")


def mitsuba_dict(name, lumagraph, tmp):
    subprocess.run([lumagraph, "export", os.path.join(ROOT, SUITE[name]["scene"]), "--out", tmp],
                   check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
    d, plugins, notes = mk.mitsuba_scene(tmp, 1, 0)
    return d, plugins, notes


def reference_mitsuba(name, lumagraph, spp, chunk):
    import mitsuba as mi
    with tempfile.TemporaryDirectory() as tmp:
        d, plugins, notes = mitsuba_dict(name, lumagraph, tmp)
        if notes:
            raise mk.Refused("; ".join(notes))
        mk.render(d, 1, 999)  # compile the kernels before timing
        start = time.time()
        halves = [None, None]
        done, k = 0, 0
        while done < spp:
            n = min(chunk, spp - done)
            img = mk.render(d, n, 1000 + k) * n
            h = 0 if done < spp // 2 else 1
            halves[h] = img if halves[h] is None else halves[h] + img
            done += n
            k += 1
            print(f"  {name}: {done}/{spp} spp, {time.time() - start:.0f} s", flush=True)
    seconds = time.time() - start
    a, b = halves[0] / (spp // 2), halves[1] / (spp - spp // 2)
    return (a + b) / 2, a, b, seconds, {
        "renderer": f"Mitsuba {mi.__version__} ({mi.variant()}), integrator path (max_depth = "
                    "bounces + 1, rr_depth 5), independent sampler, box filter, from "
                    "`lumagraph export` mapped by scripts/references/make.py",
        "plugins": plugins}


def lumagraph_render(lumagraph, graph, scene, spp, out, sets=()):
    cmd = [lumagraph, "render", graph, "--scene", scene, "--spp", str(spp), "--out", out]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)


def seeded_scene(scene, seed):
    """A copy of `scene` with render seed `seed`, beside it (its relative paths hold)."""
    import re
    src = os.path.join(ROOT, scene)
    with open(src) as f:
        text = f.read()
    text, n = re.subn(r"seed:\s*\d+", f"seed: {seed}", text)
    assert n == 1, f"{scene}: no single `seed:` to replace"
    path = src[:-len(".ron")] + f".seed{seed}.ron"
    with open(path, "w") as f:
        f.write(text)
    return path


def reference_lumagraph(name, lumagraph, spp):
    """Two independent halves (scene seeds 1001 and 1002) of the default graph's accumulation."""
    halves = []
    start = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        for seed in (1001, 1002):
            scene = seeded_scene(SUITE[name]["scene"], seed)
            try:
                lumagraph_render(lumagraph, INPUTS_GRAPH, scene, spp // 2, tmp,
                                 ["pathtrace.samples_per_frame=32"])
            finally:
                os.remove(scene)
            halves.append(read_exr(os.path.join(tmp, "color.exr")))
            print(f"  {name}: seed {seed}, {spp // 2} spp, {time.time() - start:.0f} s", flush=True)
    a, b = halves
    return (a + b) / 2, a, b, time.time() - start, {
        "renderer": f"lumagraph, {INPUTS_GRAPH} (the default graph's PathTrace + Accumulate, "
                    "32 samples a frame), two renders of spp/2 with scene seeds 1001 and 1002, "
                    "averaged"}


def step_refs(names, a):
    meta = load_meta()
    for name in names:
        s = SUITE[name]
        entry = {"scene": s["scene"], "reference": rel(ref_path(name))}
        if s["made_by"] == "existing":
            entry["how"] = "existing reference, see tests/reference/README.md"
            entry["spp"] = 24576
            entry["own_error"] = {"rmse": 1.2e-3, "relmse": 1.3e-5,
                                  "from": "tests/reference/README.md"}
            entry["mitsuba_converge"] = {"file": rel(converge_csv(name)),
                                         "how": "see tests/reference/README.md"}
        else:
            spp = s.get("spp", a.spp)
            if s["made_by"] == "mitsuba":
                ref, h1, h2, seconds, how = reference_mitsuba(name, a.lumagraph, spp, a.chunk)
            else:
                ref, h1, h2, seconds, how = reference_lumagraph(name, a.lumagraph, spp)
            write_exr(ref_path(name), ref)
            stored = read_exr(ref_path(name))  # half float: score against what is stored
            entry.update(how)
            entry["spp"] = spp
            entry["seconds"] = round(seconds, 1)
            # two independent halves: E[(h1 - h2)^2] = 4 var(mean of both)
            d2 = (h1 - h2) ** 2
            entry["own_error"] = {
                "rmse": float(np.sqrt(np.mean(d2) / 4)),
                "relmse": float(np.mean(d2 / (stored ** 2 + 1e-2)) / 4),
                "half_float_relmse": mk.relmse(stored, ref),
                "from": "two independent halves: relMSE(half1, half2) / 4",
            }
            print(f"{name}: {spp} spp in {seconds:.0f} s, own relMSE "
                  f"{entry['own_error']['relmse']:.2e}, RMSE {entry['own_error']['rmse']:.2e}")
        meta["scenes"].setdefault(name, {}).update(entry)
        save_meta(meta)


def oidn(color, albedo=None, normal=None, clean_aux=True):
    """OIDN 2.5 RT filter on the CPU, hdr, quality high; with `clean_aux` the auxiliary
    images are taken as noise-free (cleanAux), else as noisy (OIDN's mode for noisy guides,
    which does not filter them first: that is the OIDN node's `prefilter`)."""
    import pyoidn
    f32 = lambda x: None if x is None else np.ascontiguousarray(x, dtype=np.float32)
    return pyoidn.denoise(f32(color), f32(albedo), f32(normal), hdr=True,
                          clean_aux=clean_aux and albedo is not None,
                          quality="high").astype(np.float64)


def timed_oidn(color, albedo, normal, runs):
    out, times = None, []
    for _ in range(runs):
        t = time.perf_counter()
        out = oidn(color, albedo, normal)
        times.append(time.perf_counter() - t)
    return out, float(np.median(times))


def flip(x, ref):
    """Mean LDR-FLIP of sRGB-encoded images clipped to [0, 1] (flip-evaluator)."""
    import flip_evaluator
    srgb = lambda v: np.where(v <= 0.0031308, 12.92 * v,
                              1.055 * np.power(np.clip(v, 0.0031308, None), 1 / 2.4) - 0.055)
    enc = lambda v: np.ascontiguousarray(np.clip(srgb(np.clip(v, 0, 1)), 0, 1), dtype=np.float32)
    return float(flip_evaluator.evaluate(enc(ref), enc(x), "LDR", applyMagma=False)[1])


def converge_csv(name):
    if name == "cornell":
        return os.path.join(ROOT, "tests", "reference", "cornell_converge.csv")
    return os.path.join(OUT, name + "_converge.csv")


def step_mitsuba(names, a):
    """Mitsuba at 1..256 spp (seed 0, wall seconds after a warm-up) and OIDN on each image,
    guided by Mitsuba's first-hit albedo and shading normal (aov integrator, 256 spp)."""
    import mitsuba as mi
    meta = load_meta()
    for name in names:
        if name == "cornell":
            continue  # tests/reference/cornell_converge.csv exists
        ref = read_exr(ref_path(name))
        with tempfile.TemporaryDirectory() as tmp:
            d, _, notes = mitsuba_dict(name, a.lumagraph, tmp)
            if notes:
                print(f"{name}: no Mitsuba converge CSV: {'; '.join(notes)}")
                continue
            aov = {**d, "integrator": {"type": "aov", "aovs": "albedo:albedo,nn:sh_normal"},
                   "sensor": {**d["sensor"], "sampler": {"type": "independent",
                                                         "sample_count": 256}}}
            aov = np.array(mi.render(mi.load_dict(aov), spp=256), dtype=np.float64)
            albedo, normal = aov[..., 0:3], aov[..., 3:6]
            assert aov.shape[-1] == 6, aov.shape
            scene = mi.load_dict(d)
            rows = []
            spp = 1
            while spp <= 256:
                mi.render(scene, spp=spp, seed=999).numpy()  # compile this spp's kernels
                t = time.perf_counter()
                img = np.array(mi.render(scene, spp=spp, seed=0), dtype=np.float64)[..., :3]
                seconds = time.perf_counter() - t
                den, osec = timed_oidn(img, albedo, normal, 1)
                rows.append([spp, seconds, rmse(img, ref), mk.relmse(img, ref), flip(img, ref),
                             osec, rmse(den, ref), mk.relmse(den, ref), flip(den, ref)])
                print(f"  {name}: Mitsuba {spp} spp {seconds:.2f} s relMSE {rows[-1][3]:.3e}, "
                      f"OIDN {rows[-1][7]:.3e}", flush=True)
                spp *= 2
        with open(converge_csv(name), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["spp", "seconds", "rmse", "relmse", "flip", "oidn_seconds", "oidn_rmse",
                        "oidn_relmse", "oidn_flip"])
            for r in rows:
                w.writerow([r[0]] + [f"{v:.6g}" for v in r[1:]])
        meta["scenes"].setdefault(name, {})["mitsuba_converge"] = {
            "file": rel(converge_csv(name)),
            "how": "Mitsuba path (as the reference) at 1, 2 .. 256 spp, seed 0, wall seconds "
                   "of mi.render (scene loaded, kernels compiled by an untimed render first); OIDN 2.5 (RT, hdr, high, cleanAux) on each "
                   "image with Mitsuba's albedo and sh_normal AOVs (aov integrator, 256 spp); "
                   "flip: mean LDR-FLIP (flip-evaluator) of the sRGB images clipped to [0, 1]"}
        save_meta(meta)


def step_inputs(names, a):
    """lumagraph's accumulation at 4, 16, 64 spp and every denoiser on it -> baseline.csv."""
    rows = []
    path = os.path.join(OUT, "baseline.csv")
    if os.path.exists(path):  # keep the rows of scenes not asked for
        with open(path) as f:
            rows = [r for r in csv.DictReader(f) if r["scene"] not in names]
    for name in names:
        ref = read_exr(ref_path(name))
        for spp in SPPS:
            with tempfile.TemporaryDirectory() as tmp:
                lumagraph_render(a.lumagraph, INPUTS_GRAPH, SUITE[name]["scene"], spp, tmp)
                color, denoised, regressed, albedo, normal = (
                    read_exr(os.path.join(tmp, f + ".exr"))
                    for f in ("color", "denoised", "regressed", "albedo", "normal"))
            den, seconds = timed_oidn(color, albedo, normal, 3)
            noaov = oidn(color)
            prefiltered = oidn(color, albedo, normal, clean_aux=False)
            r = {"scene": name, "spp": spp,
                 "raw_relmse": mk.relmse(color, ref),
                 "atrous_relmse": mk.relmse(denoised, ref),
                 "regression_relmse": mk.relmse(regressed, ref),
                 "oidn_relmse": mk.relmse(den, ref),
                 "oidn_prefilter_relmse": mk.relmse(prefiltered, ref),
                 "oidn_noaov_relmse": mk.relmse(noaov, ref),
                 "oidn_seconds": seconds}
            print(f"  {name} {spp} spp: raw {r['raw_relmse']:.3e}, a-trous "
                  f"{r['atrous_relmse']:.3e}, regression {r['regression_relmse']:.3e}, OIDN {r['oidn_relmse']:.3e} (noisy-aux mode "
                  f"{r['oidn_prefilter_relmse']:.3e}, no AOVs "
                  f"{r['oidn_noaov_relmse']:.3e}), OIDN {seconds:.3f} s", flush=True)
            rows.append(r)
    order = list(SUITE)
    rows.sort(key=lambda r: (order.index(r["scene"]), int(r["spp"])))
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        cols = ["scene", "spp", "raw_relmse", "atrous_relmse", "regression_relmse", "oidn_relmse",
                "oidn_prefilter_relmse", "oidn_noaov_relmse", "oidn_seconds"]
        w.writerow(cols)
        for r in rows:
            w.writerow([r["scene"], r["spp"]] + [f"{float(r[c]):.6g}" for c in cols[2:]])
    meta = load_meta()
    meta["baseline"] = {
        "file": rel(path),
        "lumagraph": f"{INPUTS_GRAPH} (the default graph {DEFAULT_GRAPH} with its inputs as "
                     f"files), `lumagraph render --spp N`, the scene's seed ({SEED}); raw: "
                     "Accumulate.color, atrous: Denoise.color, regression: "
                     "RegressionDenoise.color",
        "oidn": "OIDN 2.5.1 (pyoidn), RT filter, hdr, quality high, CPU; with lumagraph's "
                "GBuffer albedo and normal (first hit, noise-free: cleanAux) on the same "
                "accumulation; oidn_prefilter: the same with cleanAux off (OIDN's mode for "
                "noisy aux images, the node's clean_aux: false; it does not filter them "
                "first); oidn_noaov: colour alone; oidn_seconds: median of 3 calls "
                "of the first (filter built before)",
        "relmse": "mean over pixels and RGB of (x - ref)^2 / (ref^2 + 1e-2)",
    }
    save_meta(meta)


def step_timing(names, a):
    """OIDN per frame (RT, hdr, albedo + normal) at 256x256 and 1920x1080 on noise."""
    import pyoidn  # noqa: F401
    rng = np.random.default_rng(0)
    out = {"load_average_before": round(os.getloadavg()[0], 2)}
    for w, h in ((256, 256), (1920, 1080)):
        color = rng.exponential(0.5, (h, w, 3)).astype(np.float32)
        albedo = rng.uniform(0, 1, (h, w, 3)).astype(np.float32)
        normal = np.zeros((h, w, 3), np.float32)
        normal[..., 2] = 1
        oidn(color, albedo, normal)  # the first call builds the filter
        times = []
        for _ in range(a.runs):
            t = time.perf_counter()
            oidn(color, albedo, normal)
            times.append(time.perf_counter() - t)
        out[f"{w}x{h}"] = {"median_seconds": float(np.median(times)),
                           "runs": [round(t, 4) for t in times]}
        print(f"  OIDN {w}x{h}: median {np.median(times):.3f} s of {a.runs}")
    meta = load_meta()
    meta["oidn_timing"] = {
        **out,
        "how": "pyoidn 2.5.1, CPU device (default threads: all cores), RT filter, hdr, quality "
               "high, albedo + normal, float32; the filter is built once, each run is one "
               "denoise call including the copies in and out",
        "cpu": cpu_name(), "cores": os.cpu_count(),
        "load_average_after": round(os.getloadavg()[0], 2),
    }
    save_meta(meta)


def step_converge(names, a):
    """`lumagraph converge` per scene of the inputs graph (raw, a-trous, regression and OIDN
    node curves): the plot (docs/images/denoise_NAME.png) and a check that baseline.csv's
    figures are what converge scores at those spp (pyoidn's against the OIDN node's: the
    same library on the same accumulation)."""
    import shutil
    with open(os.path.join(OUT, "baseline.csv")) as f:
        base = list(csv.DictReader(f))
    for name in names:
        out = os.path.join(a.converge_out, "converge_" + name)
        cmd = [a.lumagraph, "converge", INPUTS_GRAPH, "--scene", SUITE[name]["scene"],
               "--reference", rel(ref_path(name)), "--seconds", str(a.seconds), "--out", out]
        if os.path.exists(converge_csv(name)):
            cmd += ["--compare", rel(converge_csv(name))]
        if a.reuse_converge and os.path.exists(os.path.join(out, "converge.csv")):
            print(f"  {name}: reusing {out}")
        else:
            print("  " + " ".join(cmd[1:]), flush=True)
            subprocess.run(cmd, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
        os.makedirs(os.path.join(ROOT, "docs", "images"), exist_ok=True)
        shutil.copy(os.path.join(out, "converge.png"),
                    os.path.join(ROOT, "docs", "images", f"denoise_{name}.png"))
        with open(os.path.join(out, "converge.csv")) as f:
            conv = {(r["output"], int(r["spp"])): float(r["relmse"]) for r in csv.DictReader(f)}
        for r in base:
            if r["scene"] != name:
                continue
            spp = int(r["spp"])
            for col, port in (("raw_relmse", "accumulate"), ("atrous_relmse", "denoise"),
                              ("regression_relmse", "regression"), ("oidn_relmse", "oidn")):
                if (port, spp) not in conv:
                    print(f"  {name}: converge stopped before {spp} spp")
                    continue
                ours, theirs = float(r[col]), conv[(port, spp)]
                ok = abs(ours - theirs) <= 1e-3 * theirs
                print(f"  {name} {spp} spp {col}: baseline {ours:.5e}, converge {theirs:.5e}"
                      + ("" if ok else "  MISMATCH"))
                if not ok:
                    sys.exit(f"{name}: baseline.csv does not match lumagraph converge")


def cpu_name():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("names", nargs="*", help="suite scenes (default: all): " + ", ".join(SUITE))
    p.add_argument("--steps", nargs="+", default=["refs", "mitsuba", "inputs", "converge", "timing"],
                   choices=["refs", "mitsuba", "inputs", "converge", "timing"])
    p.add_argument("--lumagraph", default=os.path.join(ROOT, "target", "release", "lumagraph"))
    p.add_argument("--spp", type=int, default=8192, help="reference samples per pixel")
    p.add_argument("--chunk", type=int, default=512, help="samples per Mitsuba render call")
    p.add_argument("--runs", type=int, default=5, help="OIDN timing runs")
    p.add_argument("--seconds", type=float, default=60, help="`lumagraph converge` budget")
    p.add_argument("--converge-out", default=tempfile.gettempdir(),
                   help="where the converge_NAME folders go")
    p.add_argument("--reuse-converge", action="store_true",
                   help="take converge_NAME/converge.csv from an earlier run if it is there")
    a = p.parse_args()
    a.lumagraph = os.path.abspath(a.lumagraph)
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    names = a.names or list(SUITE)
    steps = {"refs": step_refs, "mitsuba": step_mitsuba, "inputs": step_inputs,
             "converge": step_converge, "timing": step_timing}
    for step in a.steps:
        if step in steps:
            steps[step](names, a)


if __name__ == "__main__":
    main()
