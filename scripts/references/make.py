#!/usr/bin/env python3
"""Mitsuba 3 references for the path tracer's test suite (tests/scenes/*.ron).

For each scene: `lumagraph export` writes the resolved scene (what the path tracer renders:
materials, analytic shapes, triangles as OBJ, lights, environment, camera) as JSON; this script maps
it onto Mitsuba 3 plugins, renders a reference at `--spp` samples per pixel and Mitsuba's own
256-spp images with `--seeds` seeds, and writes into tests/reference/suite/:

  NAME.exr   the reference, linear RGB, half float
  NAME.json  how it was made: spp, Mitsuba version and variant, the plugin each material
             became, and Mitsuba's relMSE at 256 spp against the reference (per seed and
             mean): the figure the tests hold lumagraph to (1.25x).

Usage (from the repository root):
  python3 -m venv .venv-mitsuba && .venv-mitsuba/bin/pip install -r scripts/references/requirements.txt
  cargo build --release
  .venv-mitsuba/bin/python scripts/references/make.py                 # every scene
  .venv-mitsuba/bin/python scripts/references/make.py conductors      # some scenes

Materials map one to one or the scene is refused (never an approximation in silence):
  specular 0, metallic 0, transmission 0          -> diffuse
  metallic 1 with eta/k (conductor presets)       -> conductor / roughconductor (GGX)
  transmission 1, metallic 0                       -> dielectric / roughdielectric (GGX)
  metallic 0, transmission 0, specular > 0         -> principled (base_color, roughness,
                                                      specular: F0 = 0.08 specular in both):
                                                      NOT the same model as lumagraph's layer
                                                      (see docs/pathtracer.md), flagged in the
                                                      JSON; --layer roughplastic maps it to
                                                      plastic / roughplastic instead
Rough lobes need `multiscatter: false` to be the same model as Mitsuba's (which has no
multiple-scattering compensation); a rough lobe with it on is flagged too.

Textures: a diffuse material's base colour texture (white factor) becomes a `bitmap` (the
exported sRGB PNG, its wrap mode and filter) for `reflectance`; its opacity (alpha `mask` or
`blend`, exported as a linear grey PNG, 0 or 1 per texel for a mask) a `mask` BSDF around it
(Mitsuba's mask is stochastic, so a mask's edge is cut between texels where lumagraph cuts at
the filtered alpha: a sub-texel difference). Any other texture, a tinted textured base colour,
vertex colours or a textured emission are refused. A two-sided material is wrapped in
`twosided` (lumagraph's opaque surfaces are black from behind unless two-sided, as Mitsuba's).
A scene with cut-outs renders with `volpath` (shadow rays cross the cut-outs, and crossing
does not count as a bounce, as in lumagraph).

A scene file elsewhere (a path ending in `.ron`) writes its reference into `--out`, e.g. the
Crytek Sponza of docs/benchmarks.md:

  .venv-mitsuba/bin/python scripts/references/make.py path/to/sponza_diffuse.ron --out out/sponza

Media: a material's `medium` (or `attenuation_*`, exported as a medium of sigma_s 0) becomes
the shape's `interior`, a `homogeneous` medium (sigma_t = sigma_a + sigma_s, albedo =
sigma_s / sigma_t, `hg` phase function); an `index_matched` material becomes the `null`
BSDF. A scene with a medium renders with `volpath` instead of `path` (the same depth
counting: medium scattering counts as a bounce, crossing a null boundary does not).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCENES = os.path.join(ROOT, "tests", "scenes")
OUT = os.path.join(ROOT, "tests", "reference", "suite")
ALPHA_MIN = 1e-3  # below this alpha lumagraph's lobes are perfect mirrors / interfaces
LAYER = "principled"  # what the dielectric layer maps to (--layer)


class Refused(Exception):
    pass


def rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def bitmap(export_dir, t, raw):
    """Mitsuba `bitmap` texture for an exported texture."""
    if t["wrap"][0] != t["wrap"][1]:
        raise Refused(f"texture {t['file']}: wrap modes {t['wrap']} differ along U and V "
                      "(Mitsuba's bitmap has one)")
    return {"type": "bitmap", "filename": os.path.join(export_dir, t["file"]),
            "wrap_mode": t["wrap"][0], "filter_type": t["filter"], "raw": raw}


def bsdf(m, export_dir="."):
    """Mitsuba BSDF dict for a lumagraph material, and notes on the mapping."""
    notes = []
    if m.get("other_textures"):
        raise Refused(f"material {m['name']}: textures {m['other_textures']} have no mapping "
                      "here (only a diffuse base colour texture and its opacity)")
    if m.get("emission_textured") and max(m["emission"]) > 0:
        raise Refused(f"material {m['name']}: a textured emission has no mapping here")
    if m["textured"] and m.get("base_color_texture") is None:
        raise Refused(f"material {m['name']}: textured materials have no mapping here")
    if m.get("index_matched"):
        return {"type": "null"}, notes
    if m.get("clearcoat", 0.0) > 0.0 or max(m.get("sheen_color", [0.0])) > 0.0:
        raise Refused(f"material {m['name']}: clear coat and sheen (the glTF lobes) have no "
                      "Mitsuba equivalent (principled's are other models)")
    if any(c != 1.0 for c in m.get("specular_color", [1.0, 1.0, 1.0])):
        raise Refused(f"material {m['name']}: a specular colour (glTF's, on F0 only) has no "
                      "Mitsuba equivalent")
    alpha = m["roughness"] ** 2
    smooth = alpha < ALPHA_MIN
    metallic, transmission, specular = m["metallic"], m["transmission"], m["specular"]
    rough_lobe = False
    if metallic == 1.0:
        if m["eta"] is None:
            raise Refused(f"material {m['name']}: a Schlick metal (base_color) has no Mitsuba "
                          "equivalent; give `conductor` or `eta`/`k`")
        d = {"type": "conductor" if smooth else "roughconductor",
             "eta": rgb(m["eta"]), "k": rgb(m["k"])}
        rough_lobe = not smooth
    elif metallic == 0.0 and transmission == 1.0:
        d = {"type": "dielectric" if smooth else "roughdielectric",
             "int_ior": float(m["ior"]), "ext_ior": 1.0,
             "specular_transmittance": rgb(m["base_color"])}
        rough_lobe = not smooth
    elif metallic == 0.0 and transmission == 0.0 and specular == 0.0:
        reflectance = rgb(m["base_color"])
        if m.get("base_color_texture"):
            if any(c != 1.0 for c in m["base_color"]):
                raise Refused(f"material {m['name']}: a base colour texture times a factor "
                              f"{m['base_color']} (Mitsuba's bitmap has no factor)")
            reflectance = bitmap(export_dir, m["base_color_texture"], raw=False)
        d = {"type": "diffuse", "reflectance": reflectance}
        return with_opacity(m, export_dir, two_sided(m, d)), notes
    elif metallic == 0.0 and transmission == 0.0 and m["specular_tint"] == 0.0 and LAYER == "principled":
        d = {"type": "principled", "base_color": rgb(m["base_color"]),
             "roughness": float(m["roughness"]), "specular": float(specular), "metallic": 0.0}
        notes.append("model differs: lumagraph's dielectric layer (GGX with Schlick F0 = 0.08 "
                     "specular over a Lambertian base that gets exactly the energy the specular "
                     "leaves) against Mitsuba's principled (Disney: retro-reflective diffuse, "
                     "uncoupled specular; reflects more than it receives)")
        return d, notes
    elif metallic == 0.0 and transmission == 0.0 and m["specular_tint"] == 0.0:
        f0 = min(0.08 * specular, 0.999)
        ior = (1 + math.sqrt(f0)) / (1 - math.sqrt(f0))
        d = {"type": "plastic" if smooth else "roughplastic", "int_ior": ior, "ext_ior": 1.0,
             "diffuse_reflectance": rgb(m["base_color"]), "nonlinear": False}
        notes.append("model differs: lumagraph's dielectric layer (Schlick F0 = 0.08 specular, "
                     "energy-coupled Lambertian base) against Mitsuba's plastic (exact Fresnel "
                     f"of ior {ior:.4f}, internal reflection, 1/eta^2; single-scattering rough "
                     "interface)")
    else:
        raise Refused(f"material {m['name']}: mixture metallic {metallic}, transmission "
                      f"{transmission} has no single Mitsuba plugin")
    if m.get("base_color_texture"):
        raise Refused(f"material {m['name']}: a base colour texture on a {d['type']} has no "
                      "mapping here")
    if m.get("alpha_mode", "opaque") != "opaque":
        raise Refused(f"material {m['name']}: opacity on a {d['type']} has no mapping here")
    if not smooth and d["type"] != "diffuse":
        d["alpha"] = alpha
        d["distribution"] = "ggx"
    if rough_lobe and m["multiscatter"]:
        notes.append("model differs: multiple-scattering compensation on (Mitsuba has none)")
    return d, notes


def two_sided(m, d):
    """`d` shaded from both sides where the material is two-sided."""
    return {"type": "twosided", "bsdf": d} if m.get("two_sided") else d


def with_opacity(m, export_dir, d):
    """`d` inside a `mask` BSDF where the material's opacity cuts or blends it."""
    mode = m.get("alpha_mode", "opaque")
    if mode == "opaque":
        return d
    if m.get("opacity_texture"):
        opacity = bitmap(export_dir, m["opacity_texture"], raw=True)
    elif mode == "mask":
        opacity = 1.0 if m["opacity"] >= m["alpha_cutoff"] else 0.0
    else:
        opacity = m["opacity"]
    return {"type": "mask", "opacity": opacity, "bsdf": d}


def describe(b):
    """A BSDF dict's plugin, with those it wraps: `mask(twosided(diffuse))`."""
    return b["type"] + (f"({describe(b['bsdf'])})" if "bsdf" in b else "")


def has_cutouts(s):
    return any(m.get("alpha_mode", "opaque") != "opaque" for m in s["materials"])


def medium(m):
    """Mitsuba `homogeneous` medium for a material's interior, or None."""
    med = m.get("medium")
    if med is None:
        return None
    sigma_t = [a + b for a, b in zip(med["sigma_a"], med["sigma_s"])]
    albedo = [s / t if t > 0 else 0.0 for s, t in zip(med["sigma_s"], sigma_t)]
    # RGB values of a medium are read as reflectances (in [0, 1]): the extinction goes in
    # as sigma_t / its largest channel, times that as `scale`.
    scale = max(sigma_t)
    return {"type": "homogeneous", "sigma_t": rgb([t / scale for t in sigma_t]),
            "albedo": rgb(albedo), "scale": float(scale),
            "phase": {"type": "hg", "g": float(med["g"])}}


def rotation(axis, degrees):
    import mitsuba as mi
    return mi.ScalarTransform4f().rotate(axis, degrees)


def mitsuba_scene(export_dir, spp, seed):
    import mitsuba as mi
    T = mi.ScalarTransform4f
    with open(os.path.join(export_dir, "scene.json")) as f:
        s = json.load(f)
    c, r = s["camera"], s["render"]
    sensor = {
        "type": "thinlens" if c["aperture_radius"] > 0 else "perspective",
        "fov": c["fov_y"], "fov_axis": "y",
        "to_world": T().look_at(origin=c["position"], target=c["target"], up=c["up"]),
        "film": {"type": "hdrfilm", "width": r["width"], "height": r["height"],
                 "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
    }
    if c["aperture_radius"] > 0:
        sensor["aperture_radius"] = c["aperture_radius"]
        sensor["focus_distance"] = c["focus_distance"]
    has_media = any(m.get("medium") is not None for m in s["materials"])
    d = {"type": "scene",
         "integrator": {"type": "volpath" if has_media or has_cutouts(s) else "path",
                        "max_depth": r["max_bounces"] + 1, "rr_depth": 5},
         "sensor": sensor}
    plugins, notes = {}, []
    mats = s["materials"]

    def material(i):
        b, n = bsdf(mats[i], export_dir)
        plugins[mats[i]["name"]] = describe(b)
        notes.extend(f"{mats[i]['name']}: {x}" for x in n if x not in notes)
        return b

    def emitter(i):
        m = mats[i]
        if max(m["emission"]) <= 0:
            return None
        if m["two_sided"]:
            raise Refused(f"material {m['name']}: two-sided emitters are one-sided in Mitsuba")
        return {"type": "area", "radiance": rgb(m["emission"])}

    for k, mesh in enumerate(s["meshes"]):
        if mesh.get("vertex_colors"):
            raise Refused(f"{mesh['file']}: vertex colours have no mapping here")
        shape = {"type": "obj", "filename": os.path.join(export_dir, mesh["file"]),
                 "face_normals": not mesh["smooth"], "bsdf": material(mesh["material"])}
        e = emitter(mesh["material"])
        if e:
            shape["emitter"] = e
        inside = medium(mats[mesh["material"]])
        if inside:
            shape["interior"] = inside
        d[f"mesh_{k}"] = shape
    for k, sh in enumerate(s["shapes"]):
        # Each kind of analytic shape exports its own Mitsuba dictionary.
        shape = dict(sh["mitsuba"])
        if "to_world" in shape:
            shape["to_world"] = T(shape["to_world"])
        shape["bsdf"] = material(sh["material"])
        e = emitter(sh["material"])
        if e:
            shape["emitter"] = e
        inside = medium(mats[sh["material"]])
        if inside:
            shape["interior"] = inside
        d[f"{sh['kind']}_{k}"] = shape
    for k, l in enumerate(s["lights"]):
        # A light without area: its kind's Mitsuba emitter (crates/scene/src/lights/), as is.
        light = dict(l["mitsuba"])
        if "to_world" in light:
            light["to_world"] = T(light["to_world"])
        d[f"light_{k}"] = light
    env = s["environment"]
    if env["type"] == "constant":
        d["environment"] = {"type": "constant", "radiance": rgb(env["radiance"])}
    elif env["type"] == "map":
        if not env["show_background"]:
            raise Refused("show_background: false has no Mitsuba equivalent here")
        d["environment"] = {"type": "envmap", "filename": env["path"], "scale": env["intensity"],
                            "to_world": T().rotate([0, 1, 0], env["azimuth"])
                            @ T().rotate([1, 0, 0], env["elevation"])}
    return d, plugins, notes


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 1e-2)))


def render(d, spp, seed):
    import mitsuba as mi
    d = dict(d)
    d["sensor"] = dict(d["sensor"])
    d["sensor"]["sampler"] = {"type": "independent", "sample_count": spp, "seed": seed}
    scene = mi.load_dict(d)
    return np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)[..., :3]


def make(name, lumagraph, spp, chunk, seeds, out=OUT):
    import mitsuba as mi
    if name.endswith(".ron"):
        src = os.path.abspath(name)
        name = os.path.basename(name)[:-4]
    else:
        src = os.path.join(SCENES, name + ".ron")
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([lumagraph, "export", src, "--out", tmp], check=True,
                       stdout=subprocess.DEVNULL)
        d, plugins, notes = mitsuba_scene(tmp, chunk, 0)
        render(d, 1, 999)  # compile the kernels before timing
        start = time.time()
        acc, done, k = None, 0, 0
        while done < spp:
            n = min(chunk, spp - done)
            img = render(d, n, 1000 + k) * n
            acc = img if acc is None else acc + img
            done += n
            k += 1
            print(f"  {name}: {done}/{spp} spp, {time.time() - start:.0f} s", flush=True)
        ref = acc / spp
        seconds = time.time() - start
        per_seed = []
        for s in range(seeds):
            t = time.time()
            img = render(d, 256, s)
            per_seed.append({"seed": s, "relmse": relmse(img, ref), "seconds": time.time() - t})
    os.makedirs(out, exist_ok=True)
    bmp = mi.Bitmap(ref.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp = bmp.convert(component_format=mi.Struct.Type.Float16)
    bmp.write(os.path.join(out, name + ".exr"))
    scene = os.path.relpath(src, ROOT)
    meta = {
        "scene": scene if not scene.startswith("..") else os.path.basename(src),
        "renderer": f"Mitsuba {mi.__version__} ({mi.variant()}), integrator "
                    f"{d['integrator']['type']}, independent sampler, box filter",
        "spp": spp,
        "seconds": round(seconds, 1),
        "plugins": plugins,
        "model_differences": notes,
        "mitsuba_relmse_256": {"mean": float(np.mean([p["relmse"] for p in per_seed])),
                               "per_seed": per_seed},
    }
    with open(os.path.join(out, name + ".json"), "w") as f:
        json.dump(meta, f, indent=1)
        f.write("\n")
    print(f"{name}: {spp} spp in {seconds:.0f} s, Mitsuba relMSE at 256 spp "
          f"{meta['mitsuba_relmse_256']['mean']:.3e}; plugins {sorted(set(plugins.values()))}"
          + ("".join(f"\n  note: {n}" for n in notes)))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("scenes", nargs="*",
                   help="scene names in tests/scenes (default: all), or scene files (.ron)")
    p.add_argument("--out", default=OUT, help="folder of the references written")
    p.add_argument("--lumagraph", default=os.path.join(ROOT, "target", "release", "lumagraph"))
    p.add_argument("--spp", type=int, default=16384, help="reference samples per pixel")
    p.add_argument("--chunk", type=int, default=1024, help="samples per Mitsuba render call")
    p.add_argument("--seeds", type=int, default=4, help="seeds of Mitsuba's 256-spp images")
    p.add_argument("--layer", choices=["principled", "roughplastic"], default="principled",
                   help="Mitsuba plugin for lumagraph's dielectric layer")
    a = p.parse_args()
    global LAYER
    LAYER = a.layer
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    names = a.scenes or sorted(f[:-4] for f in os.listdir(SCENES) if f.endswith(".ron"))
    failed = []
    for name in names:
        try:
            make(name, a.lumagraph, a.spp, a.chunk, a.seeds, a.out)
        except Refused as e:
            print(f"{name}: refused: {e}", file=sys.stderr)
            failed.append(name)
    if failed:
        sys.exit(f"no reference for: {', '.join(failed)}")


if __name__ == "__main__":
    main()
