#!/usr/bin/env python3
"""The reduced Crytek Sponza of assets/sponza-small/, made from the full one.

Keeps the whole geometry (Sponza.bin unchanged: 262 087 triangles drawn through 174 nodes),
the cameras and the materials with their alpha modes, and only the base colour textures,
downscaled to at most --size texels a side (Lanczos, alpha kept): what a diffuse reduction
of the scene (`Mesh(..., diffuse: true)`) reads, small enough for the repository and a test
(tests/scenes/sponza_diffuse.ron, held to its Mitsuba reference by tests/mitsuba_suite.rs).

  python3 scripts/sponza_small.py path/to/Sponza assets/sponza-small    # needs Pillow

The source: the glTF Sponza described in its SOURCE.md (AMD's Capsaicin test media, vendor
extensions mapped to core glTF); CC BY 3.0, as the copy is.
"""
import argparse
import json
import os
import shutil

from PIL import Image


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("source", help="folder with Sponza.gltf, Sponza.bin and the images")
    p.add_argument("out", help="folder to write")
    p.add_argument("--size", type=int, default=128, help="largest texture side")
    a = p.parse_args()
    with open(os.path.join(a.source, "Sponza.gltf")) as f:
        g = json.load(f)
    used = []
    for m in g["materials"]:
        for key in ("normalTexture", "occlusionTexture", "emissiveTexture"):
            m.pop(key, None)
        pbr = m.get("pbrMetallicRoughness", {})
        pbr.pop("metallicRoughnessTexture", None)
        if "baseColorTexture" in pbr:
            used.append(pbr["baseColorTexture"]["index"])
    # Textures renumbered: only those the base colours read, in first-use order.
    order = list(dict.fromkeys(used))
    textures = [g["textures"][t] for t in order]
    for m in g["materials"]:
        pbr = m.get("pbrMetallicRoughness", {})
        if "baseColorTexture" in pbr:
            pbr["baseColorTexture"]["index"] = order.index(pbr["baseColorTexture"]["index"])
    images_used = list(dict.fromkeys(t["source"] for t in textures))
    os.makedirs(a.out, exist_ok=True)
    images = []
    for i in images_used:
        src = g["images"][i]["uri"]
        img = Image.open(os.path.join(a.source, src))
        img = img.convert("RGBA" if "A" in img.getbands() else "RGB")
        scale = a.size / max(img.size)
        if scale < 1:
            size = (max(1, round(img.size[0] * scale)), max(1, round(img.size[1] * scale)))
            img = img.resize(size, Image.Resampling.LANCZOS)
        name = os.path.splitext(os.path.basename(src))[0] + ".png"
        img.save(os.path.join(a.out, name), optimize=True)
        images.append({"uri": name})
    for t in textures:
        t["source"] = images_used.index(t["source"])
    g["textures"], g["images"] = textures, images
    g.setdefault("asset", {}).setdefault("extras", {})["reduced"] = (
        f"base colour textures only, at most {a.size} texels a side "
        "(scripts/sponza_small.py)")
    with open(os.path.join(a.out, "Sponza.gltf"), "w") as f:
        json.dump(g, f, indent=1)
        f.write("\n")
    for name in ("Sponza.bin", "SponzaLicense.txt"):
        shutil.copy(os.path.join(a.source, name), os.path.join(a.out, name))
    print(f"{len(images)} images, {len(g['materials'])} materials -> {a.out}")


if __name__ == "__main__":
    main()
